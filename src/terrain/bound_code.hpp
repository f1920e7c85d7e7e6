#pragma once
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace ps::terrain {

// Error and radius bounds are stored as 16-bit codes so that an 8193^2 planet's heights plus
// bounds fit in 8 bytes per vertex. A code always decodes to a value >= the value it encoded
// (rounding goes up), so a stored bound stays a bound, and encoding is monotone, so nesting
// (parent >= child) survives the round trip.
//   code 0      -> 0
//   code k >= 1 -> kMin * 2^e * (1 + f / 1024), where k - 1 = 1024 e + f (0 <= f < 1024)
// A code is a float with a 6-bit exponent and a 10-bit mantissa: code k's value is the float
// whose bits are kMin's plus (k - 1) << 13, and as a double its bits are kMin's plus
// (k - 1) << 42. So encoding is a subtraction and a shift of the value's bits, rounded up, and
// decoding a shift and an add: no table, and loops of either vectorise. A code is at most
// 0.098 % above its value (0.049-0.098 % depending on where in its octave the value lies); the
// range runs from 1 micrometre (2^-20 m) to ~1.8e13 m.
class BoundCode {
 public:
  static constexpr double kMin = 1.0 / (1 << 20);
  static constexpr int kStepsPerOctave = 1024;

  static float decode(std::uint16_t code) {
    // Code 0's bits are masked to 0.0f rather than chosen by a branch: loops that decode stay
    // free of control flow, which they must be to vectorise.
    const std::uint32_t bits = kMinFloatBits + ((std::uint32_t(code) - 1u) << 13);
    return std::bit_cast<float>(bits & (0u - std::uint32_t(code != 0)));
  }

  static std::uint16_t encodeUp(double value) {
    // !(value > 0) also maps NaN to 0; callers validate heights first.
    if (!(value > kMin)) return value > 0.0 ? 1 : 0;
    if (!(value <= kMaxValue)) return 65535;  // also infinity
    const std::uint64_t steps = std::bit_cast<std::uint64_t>(value) - kMinDoubleBits;
    return std::uint16_t(((steps + kDoubleStep - 1) >> kDoubleShift) + 1);
  }

  // The smallest code whose value squared is at least `square`. The rounded root can lie just
  // below the exact one, and a code's value is a float (its square exact in double), so the
  // root's code is the answer or one below it: one comparison of squares decides.
  static std::uint16_t encodeUpFromSquare(double square) {
    const std::uint16_t code = encodeUp(std::sqrt(square));
    const double value = decode(code);
    return std::uint16_t(code + (code != 0 && code < 65535 && value * value < square ? 1 : 0));
  }

  // encodeUp / encodeUpFromSquare of values[0 .. n) (the bounds' row kernels encode a run of
  // vertices; without tables the loops vectorise).
  static void encodeUp(const double* values, std::size_t n, std::uint16_t* codes) {
    for (std::size_t k = 0; k < n; ++k) codes[k] = encodeUp(values[k]);
  }
  static void encodeUpFromSquare(const double* squares, std::size_t n, std::uint16_t* codes) {
    for (std::size_t k = 0; k < n; ++k) codes[k] = encodeUpFromSquare(squares[k]);
  }

 private:
  static constexpr std::uint32_t kMinFloatBits = std::bit_cast<std::uint32_t>(float(kMin));
  static constexpr std::uint64_t kMinDoubleBits = std::bit_cast<std::uint64_t>(kMin);
  static constexpr int kDoubleShift = 52 - 10;  // a double's mantissa bits below a code's 10
  static constexpr std::uint64_t kDoubleStep = std::uint64_t(1) << kDoubleShift;
  static constexpr double kMaxValue =
      std::bit_cast<double>(kMinDoubleBits + (std::uint64_t(65534) << kDoubleShift));
};

}  // namespace ps::terrain
