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

  // Codes one octave apart decode to exactly twice the value (the table is built that way), so
  // the first octave's 1024 floats and an exponent add give every code: a 4 KiB table that stays
  // in the L1 cache instead of a 256 KiB one that missed it on every child and every split.
  static float decode(std::uint16_t code) { return decode(table(), code); }

  static std::uint16_t encodeUp(double value) { return encodeUp(table(), value); }

  // encodeUp of values[0 .. n): one loop without calls, so the table look-ups of different
  // values overlap (the bounds' row kernels encode a run of vertices at once).
  static void encodeUp(const double* values, std::size_t n, std::uint16_t* codes) {
    const Table& t = table();
    for (std::size_t k = 0; k < n; ++k) codes[k] = encodeUp(t, values[k]);
  }

 private:
  struct Table;
  static std::uint16_t encodeUp(const Table& t, double value) {
    if (!(value > 0.0)) return 0;  // also maps NaN to 0; callers validate heights first
    if (value <= kMin) return 1;
    // value = kMin * 2^e * (1 + f). The table holds, for each of 4096 buckets of f, the first
    // code at or above the bucket's start (codes are periodic: an octave up is 1024 codes up,
    // and the float table scales exactly). A bucket spans under half a code step, so the answer
    // is that code or the next: one comparison, no loop (the loop's mispredicted exits were a
    // sixth of a bounds build; std::log2 was a fifth before that).
    const auto bits = std::bit_cast<std::uint64_t>(value / kMin);  // kMin is a power of two
    const int exponent = int((bits >> 52) & 0x7ff) - 1023;
    const int first = exponent * kStepsPerOctave + t.firstCode[(bits >> 40) & 0xfff];
    if (first >= 65535) return 65535;
    return std::uint16_t(first + (double(decode(t, std::uint16_t(first))) < value ? 1 : 0));
  }
  static float decode(const Table& t, std::uint16_t code) {
    const unsigned k = unsigned(code) - 1u;
    const auto first = std::bit_cast<std::uint32_t>(t.octave[k & (kStepsPerOctave - 1)]);
    const float value = std::bit_cast<float>(first + ((k / kStepsPerOctave) << 23));
    return code == 0 ? 0.0f : value;
  }

  struct Table {
    // octave[j] = decode(j + 1): the codes of the first octave.
    std::array<float, kStepsPerOctave> octave;
    // Smallest code k in octave 0 with values[k] >= kMin * (1 + j / 4096).
    std::array<std::uint16_t, 4096> firstCode;
    Table() {
      for (int k = 1; k <= kStepsPerOctave; ++k) {
        const double x = kMin * std::exp2(double(k - 1) / kStepsPerOctave);
        // Round the table entry up too, so decode(code) >= the exact code value.
        float f = static_cast<float>(x);
        if (double(f) < x) f = std::nextafter(f, INFINITY);
        octave[std::size_t(k - 1)] = f;
      }
      // Higher octaves double the first exactly (all within float's normal range: 2^-20 to
      // 2^44 m), so that firstCode below holds for every octave, whatever the last bit of exp2.
      int k = 0;
      for (int j = 0; j < 4096; ++j) {
        const double start = kMin * (1.0 + j / 4096.0);
        while (k < kStepsPerOctave && double(octave[std::size_t(k)]) < start) ++k;
        firstCode[std::size_t(j)] = std::uint16_t(k + 1);
      }
    }
  };
  static const Table& table() {
    static const Table t;
    return t;
  }
};

}  // namespace ps::terrain
