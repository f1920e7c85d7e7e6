#pragma once
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

namespace ps::terrain {

// Error and radius bounds are stored as 16-bit logarithmic codes so that an 8193^2 planet's
// heights plus bounds fit in 8 bytes per vertex. A code always decodes to a value >= the value
// it encoded (rounding goes up), so a stored bound stays a bound, and encoding is monotone, so
// nesting (parent >= child) survives the round trip.
//   code 0      -> 0
//   code k >= 1 -> kMin * 2^((k - 1) / kStepsPerOctave)
// With 1024 steps per octave a code is at most 0.068 % above its value; the range runs from
// 1 micrometre to ~1.7e13 m.
class BoundCode {
 public:
  static constexpr double kMin = 1.0 / (1 << 20);
  static constexpr int kStepsPerOctave = 1024;

  static float decode(std::uint16_t code) { return table().values[code]; }

  static std::uint16_t encodeUp(double value) {
    if (!(value > 0.0)) return 0;  // also maps NaN to 0; callers validate heights first
    if (value <= kMin) return 1;
    // A guess from the exponent and the top 12 mantissa bits (a bound build encodes two values
    // per vertex; std::log2 was a fifth of it), never above the answer and at most three steps
    // below it; the steps below make the result exact whatever the guess.
    const auto bits = std::bit_cast<std::uint64_t>(value / kMin);  // kMin is a power of two
    const int exponent = int((bits >> 52) & 0x7ff) - 1023;
    const double k = double(exponent) * kStepsPerOctave +
                     double(table().octaveSteps[(bits >> 40) & 0xfff]) + 1.0;
    if (k > 65535.0) return 65535;
    auto code = static_cast<std::uint32_t>(k);
    while (code < 65535 && double(decode(std::uint16_t(code))) < value) ++code;
    while (code > 1 && double(decode(std::uint16_t(code - 1))) >= value) --code;
    return std::uint16_t(code);
  }

 private:
  struct Table {
    std::array<float, 65536> values;
    // floor(kStepsPerOctave * log2(1 + j / 4096)), less one for safety against log2's rounding.
    std::array<std::uint16_t, 4096> octaveSteps;
    Table() {
      for (int j = 0; j < 4096; ++j) {
        const double steps = std::floor(kStepsPerOctave * std::log2(1.0 + j / 4096.0));
        octaveSteps[std::size_t(j)] = std::uint16_t(steps > 0 ? steps - 1 : 0);
      }
      values[0] = 0.0f;
      for (int k = 1; k < 65536; ++k) {
        const double x = kMin * std::exp2(double(k - 1) / kStepsPerOctave);
        // Round the table entry up too, so decode(code) >= the exact code value.
        float f = static_cast<float>(x);
        if (double(f) < x) f = std::nextafter(f, INFINITY);
        values[std::size_t(k)] = f;
      }
    }
  };
  static const Table& table() {
    static const Table t;
    return t;
  }
};

}  // namespace ps::terrain
