#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "terrain/bound_code.hpp"

using ps::terrain::BoundCode;

TEST(BoundCode, DecodesToABoundWithinAFractionOfAPermille) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> expo(-19.0, 40.0);
  for (int i = 0; i < 200000; ++i) {
    const double x = std::exp2(expo(rng));
    const auto code = BoundCode::encodeUp(x);
    const double back = BoundCode::decode(code);
    ASSERT_GE(back, x) << x;
    ASSERT_LE(back, x * (1.0 + 1.0 / BoundCode::kStepsPerOctave)) << x;
    if (code > 1) {
      ASSERT_LT(double(BoundCode::decode(std::uint16_t(code - 1))), x) << "smallest bounding code";
    }
  }
  EXPECT_EQ(BoundCode::encodeUp(0.0), 0);
  EXPECT_EQ(BoundCode::decode(0), 0.0f);
}

// Every code's value, and the doubles just beside it, encode to the code that bounds them: the
// exact boundaries, where rounding up by bit arithmetic is most likely to be one off.
TEST(BoundCode, CodeValuesAndTheirNeighboursEncodeExactly) {
  for (int k = 2; k < 65536; ++k) {
    const double x = BoundCode::decode(std::uint16_t(k));
    const auto c = BoundCode::encodeUp(x);
    ASSERT_GE(double(BoundCode::decode(c)), x) << k;
    ASSERT_LT(double(BoundCode::decode(std::uint16_t(c - 1))), x) << k;
    const double above = std::nextafter(x, 1e300);
    const auto ca = BoundCode::encodeUp(above);
    if (ca < 65535) {
      ASSERT_GE(double(BoundCode::decode(ca)), above) << k;
      ASSERT_LT(double(BoundCode::decode(std::uint16_t(ca - 1))), above) << k;
    }
  }
}

TEST(BoundCode, EncodingIsMonotone) {
  double prev = 0;
  std::uint16_t prevCode = 0;
  for (double x = 1e-7; x < 1e12; x *= 1.013) {
    const auto c = BoundCode::encodeUp(x);
    ASSERT_GE(c, prevCode) << prev << " -> " << x;
    prev = x, prevCode = c;
  }
}

// Against a binary search over the decoded values: random values in every octave, the octave
// boundaries (where rounding up carries into the exponent) and the doubles beside them.
TEST(BoundCode, EveryOctaveEncodesToTheSmallestBoundingCode) {
  auto smallestBound = [](double x) {
    int lo = 1, hi = 65535;  // first code whose value is >= x (saturating at 65535)
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      if (double(BoundCode::decode(std::uint16_t(mid))) >= x)
        hi = mid;
      else
        lo = mid + 1;
    }
    return std::uint16_t(lo);
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> fraction(1.0, 2.0);
  for (int e = 0; e < 64; ++e) {
    const double start = BoundCode::kMin * std::exp2(e);
    for (const double x : {start, std::nextafter(start, 0.0), std::nextafter(start, 1e300)}) {
      if (x <= BoundCode::kMin) continue;
      ASSERT_EQ(BoundCode::encodeUp(x), smallestBound(x)) << "octave " << e;
    }
    for (int i = 0; i < 2000; ++i) {
      const double x = start * fraction(rng);
      ASSERT_EQ(BoundCode::encodeUp(x), smallestBound(x)) << "octave " << e << " value " << x;
    }
  }
  // Codes an octave apart are exactly twice the value.
  for (int k = 1; k + BoundCode::kStepsPerOctave < 65536; ++k) {
    const double v = BoundCode::decode(std::uint16_t(k));
    ASSERT_EQ(double(BoundCode::decode(std::uint16_t(k + BoundCode::kStepsPerOctave))), 2 * v) << k;
  }
  EXPECT_EQ(BoundCode::encodeUp(std::numeric_limits<double>::infinity()), 65535);
  EXPECT_EQ(BoundCode::encodeUp(std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(BoundCode::encodeUp(-3.0), 0);
  EXPECT_EQ(BoundCode::encodeUp(BoundCode::kMin / 4), 1);
}

// encodeUpFromSquare gives the smallest code whose value squared bounds the square: at random
// squares over the whole range, at the squares of every code's value and the doubles beside
// them (the boundaries), and at the starts of mantissa steps of both exponent parities. Away
// from those boundaries it is encodeUp of the root.
TEST(BoundCode, FromSquareIsTheSmallestCodeWhoseSquareBounds) {
  // A result, not ASSERTs (which would end only the lambda): the first failing square ends the
  // test.
  auto check = [](double square) -> testing::AssertionResult {
    const auto c = BoundCode::encodeUpFromSquare(square);
    const double value = BoundCode::decode(c);
    if (c < 65535 && !(value * value >= square))
      return testing::AssertionFailure()
             << "square " << square << ": code " << c << " squared is " << value * value;
    if (c > 1) {
      const double below = BoundCode::decode(std::uint16_t(c - 1));
      if (!(below * below < square))
        return testing::AssertionFailure() << "square " << square << ": code " << c - 1
                                           << " below already bounds it (" << below * below << ")";
    }
    return testing::AssertionSuccess();
  };
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> expo(-45.0, 85.0);
  int sameAsRoot = 0;
  for (int i = 0; i < 200000; ++i) {
    const double square = std::exp2(expo(rng));
    ASSERT_TRUE(check(square));
    sameAsRoot += BoundCode::encodeUpFromSquare(square) == BoundCode::encodeUp(std::sqrt(square));
  }
  EXPECT_EQ(sameAsRoot, 200000);
  for (int k = 1; k < 65535; ++k) {
    const double v = BoundCode::decode(std::uint16_t(k));
    for (double square : {v * v, std::nextafter(v * v, 0.0), std::nextafter(v * v, 1e300)})
      ASSERT_TRUE(check(square));
  }
  for (int e = -40; e < 80; ++e)
    for (int j = 0; j < 4096; j += 17) ASSERT_TRUE(check(std::ldexp(1.0 + j / 4096.0, e)));
  EXPECT_EQ(BoundCode::encodeUpFromSquare(0.0), 0);
  EXPECT_EQ(BoundCode::encodeUpFromSquare(-1.0), 0);
  EXPECT_EQ(BoundCode::encodeUpFromSquare(1e-300), 1);
}
