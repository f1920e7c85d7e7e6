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
  struct Table;  // below: the first octave's values and the encoding's bucket tables

 public:
  static constexpr double kMin = 1.0 / (1 << 20);
  static constexpr int kStepsPerOctave = 1024;

  // Codes one octave apart decode to exactly twice the value (the table is built that way), so
  // the first octave's 1024 floats and an exponent add give every code: a 4 KiB table that stays
  // in the L1 cache instead of a 256 KiB one that missed it on every child and every split.
  static float decode(std::uint16_t code) { return decode(table(), code); }

  static std::uint16_t encodeUp(double value) { return encodeUp(table(), value); }

  // decode() with the table fetched once, for loops over many codes (each decode() call checks
  // that the function-local table has been built, a load and a branch per code).
  class Decoder {
   public:
    float operator()(std::uint16_t code) const { return BoundCode::decode(*table_, code); }

   private:
    friend class BoundCode;
    explicit Decoder(const Table& t) : table_(&t) {}
    const Table* table_;
  };
  static Decoder decoder() { return Decoder(table()); }

  // The smallest code whose value squared is at least `square`: the code of a distance from its
  // square, without the square root (a decoded value is a float, so its square is exact in
  // double). The same as encodeUp(std::sqrt(square)) except where the rounded root lands
  // exactly on a code's value while the exact root lies above it; there this one is the bound.
  static std::uint16_t encodeUpFromSquare(double square) {
    return encodeUpFromSquare(table(), square);
  }

  // encodeUp / encodeUpFromSquare of values[0 .. n): one loop without calls, so the table
  // look-ups of different values overlap (the bounds' row kernels encode a run of vertices).
  static void encodeUp(const double* values, std::size_t n, std::uint16_t* codes) {
    const Table& t = table();
    for (std::size_t k = 0; k < n; ++k) codes[k] = encodeUp(t, values[k]);
  }
  static void encodeUpFromSquare(const double* squares, std::size_t n, std::uint16_t* codes) {
    const Table& t = table();
    for (std::size_t k = 0; k < n; ++k) codes[k] = encodeUpFromSquare(t, squares[k]);
  }

 private:
  static std::uint16_t encodeUpFromSquare(const Table& t, double square) {
    if (!(square > 0.0)) return 0;
    if (square <= kMin * kMin) return 1;
    // square = kMin^2 * 2^e * (1 + f): the root is kMin * 2^(e/2) * sqrt(1 + f) for even e and
    // kMin * 2^((e-1)/2) * sqrt(2 (1 + f)) for odd e; one bucket table per parity. A bucket spans
    // under a quarter of a code step in the root, so one comparison finishes it.
    const auto bits = std::bit_cast<std::uint64_t>(square / (kMin * kMin));
    const int exponent = int((bits >> 52) & 0x7ff) - 1023;  // >= 0 here
    const int first = (exponent >> 1) * kStepsPerOctave +
                      t.firstCodeOfRoot[std::size_t(exponent & 1)][(bits >> 40) & 0xfff];
    if (first >= 65535) return 65535;
    const double value = decode(t, std::uint16_t(first));
    return std::uint16_t(first + (value * value < square ? 1 : 0));
  }
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
    // Smallest code k in octave 0 (or 1025, octave 1's first) with values[k]^2 >=
    // kMin^2 * 2^p * (1 + j / 4096), for p = 0, 1.
    std::array<std::array<std::uint16_t, 4096>, 2> firstCodeOfRoot;
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
      // In units of kMin (a power of two): the values are floats, so their squares are exact.
      for (int p = 0; p < 2; ++p) {
        k = 0;
        for (int j = 0; j < 4096; ++j) {
          const double start = (1.0 + j / 4096.0) * (p ? 2.0 : 1.0);
          auto unitSquare = [&](int i) {
            const double x = double(octave[std::size_t(i)]) / kMin;
            return x * x;
          };
          while (k < kStepsPerOctave && unitSquare(k) < start) ++k;
          firstCodeOfRoot[std::size_t(p)][std::size_t(j)] = std::uint16_t(k + 1);
        }
      }
    }
  };
  static const Table& table() {
    static const Table t;
    return t;
  }
};

}  // namespace ps::terrain
