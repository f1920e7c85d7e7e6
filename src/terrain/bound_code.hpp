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
    // value = kMin * 2^e * (1 + f). The table holds, for each of 4096 buckets of f, the first
    // code at or above the bucket's start (codes are periodic: an octave up is 1024 codes up,
    // and the float table scales exactly). A bucket spans under half a code step, so the answer
    // is that code or the next: one comparison, no loop (the loop's mispredicted exits were a
    // sixth of a bounds build; std::log2 was a fifth before that).
    const auto bits = std::bit_cast<std::uint64_t>(value / kMin);  // kMin is a power of two
    const int exponent = int((bits >> 52) & 0x7ff) - 1023;
    const int first = exponent * kStepsPerOctave + table().firstCode[(bits >> 40) & 0xfff];
    if (first >= 65535) return 65535;
    return std::uint16_t(first + (double(decode(std::uint16_t(first))) < value ? 1 : 0));
  }

 private:
  struct Table {
    std::array<float, 65536> values;
    // Smallest code k in octave 0 with values[k] >= kMin * (1 + j / 4096).
    std::array<std::uint16_t, 4096> firstCode;
    Table() {
      values[0] = 0.0f;
      for (int k = 1; k <= kStepsPerOctave; ++k) {
        const double x = kMin * std::exp2(double(k - 1) / kStepsPerOctave);
        // Round the table entry up too, so decode(code) >= the exact code value.
        float f = static_cast<float>(x);
        if (double(f) < x) f = std::nextafter(f, INFINITY);
        values[std::size_t(k)] = f;
      }
      // Higher octaves double the first exactly (all within float's normal range), so that
      // firstCode below holds for every octave, whatever the last bit of exp2.
      for (int k = kStepsPerOctave + 1; k < 65536; ++k)
        values[std::size_t(k)] = 2.0f * values[std::size_t(k - kStepsPerOctave)];
      int k = 1;
      for (int j = 0; j < 4096; ++j) {
        const double start = kMin * (1.0 + j / 4096.0);
        while (double(values[std::size_t(k)]) < start) ++k;
        firstCode[std::size_t(j)] = std::uint16_t(k);
      }
    }
  };
  static const Table& table() {
    static const Table t;
    return t;
  }
};

}  // namespace ps::terrain
