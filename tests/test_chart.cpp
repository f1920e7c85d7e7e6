#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"

using ps::core::GridSize;
using ps::core::InputError;
using ps::core::LatLongChart;

TEST(GridSize, AcceptsOnlyPowerOfTwoPlusOne) {
  EXPECT_EQ(GridSize::fromSide(8193).n(), 13);
  EXPECT_EQ(GridSize::fromSide(33).m(), 32);
  EXPECT_THROW(GridSize::fromSide(8192), InputError);
  EXPECT_THROW(GridSize::fromSide(0), InputError);
  EXPECT_THROW(GridSize(4), InputError);
  EXPECT_THROW(GridSize(16), InputError);
  try {
    GridSize::fromSide(1000);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1000"), std::string::npos) << "the error names the value";
  }
}

TEST(LatLongChart, RejectsBadRadius) {
  EXPECT_THROW(LatLongChart(GridSize(5), 0.0), InputError);
  EXPECT_THROW(LatLongChart(GridSize(5), -1.0), InputError);
  EXPECT_THROW(LatLongChart(GridSize(5), NAN), InputError);
}

TEST(LatLongChart, FollowsPaperEquations) {
  const LatLongChart c(GridSize(6), 2.0);
  const int m = 64;
  for (int v = 0; v <= m; v += 7) {
    for (int u = 0; u <= m; u += 5) {
      const double lat = v * std::numbers::pi / m - std::numbers::pi / 2;
      const double lon = 2.0 * u * std::numbers::pi / m - std::numbers::pi;
      const Eigen::Vector3d expect =
          2.5 * Eigen::Vector3d(std::cos(lon) * std::cos(lat), std::sin(lon) * std::cos(lat),
                                std::sin(lat));
      EXPECT_LT((c.position(u, v, 0.5) - expect).norm(), 1e-12);
      EXPECT_LT((c.positionAt(u, v, 0.5) - expect).norm(), 1e-12);
    }
  }
}

TEST(LatLongChart, SeamTwinsAndPoleRowsAreBitwiseOnePoint) {
  const LatLongChart c(GridSize(9), 6372790.0);
  const int m = c.grid().m();
  for (int v = 0; v <= m; ++v)
    EXPECT_EQ(c.position(0, v, 10.0), c.position(m, v, 10.0)) << "v=" << v;
  for (int u = 0; u <= m; ++u) {
    EXPECT_EQ(c.position(u, 0, 3.0), c.position(0, 0, 3.0)) << "south pole u=" << u;
    EXPECT_EQ(c.position(u, m, 3.0), c.position(0, m, 3.0)) << "north pole u=" << u;
  }
}

TEST(LatLongChart, InverseRecoversGridCoordinates) {
  const LatLongChart c(GridSize(8), 1000.0);
  const int m = c.grid().m();
  for (int v = 1; v < m; v += 3) {
    for (int u = 0; u < m; u += 3) {
      const auto uv = c.inverse(c.position(u, v, 20.0));
      ASSERT_TRUE(uv.has_value());
      EXPECT_NEAR((*uv).y(), v, 1e-9);
      // u = 0 and u = m are one meridian: either answer is right there.
      const double du =
          u == 0 ? std::min(std::abs((*uv).x()), std::abs((*uv).x() - m)) : std::abs((*uv).x() - u);
      EXPECT_LT(du, 1e-9) << u << "," << v;
    }
  }
  EXPECT_FALSE(c.inverse(Eigen::Vector3d::Zero()).has_value());
  EXPECT_FALSE(c.inverse(Eigen::Vector3d(NAN, 0, 0)).has_value());
}

// The tessellator computes a level's positions with scatteredPositions (vectorised, and cloned
// for AVX2 / AVX-512): they must be position()'s, bit for bit, or the mesh's vertices and its
// split decisions would depend on the machine. Random vertices, the seam and the poles included,
// and a count that leaves a remainder after any vector width.
TEST(Chart, ScatteredPositionsAreBitwisePositions) {
  const LatLongChart latlong(GridSize(10), 6372790.0);
  const ps::core::FlatChart flat(GridSize(10), 250.0, 125.0);
  const int m = latlong.grid().m();
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(0, m);
  std::uniform_real_distribution<float> height(-8000.0f, 8000.0f);
  std::vector<std::int32_t> u, v;
  std::vector<float> h;
  for (int k = 0; k < 1001; ++k) {
    u.push_back(k % 7 == 0 ? (k % 2) * m : coord(rng));
    v.push_back(k % 11 == 0 ? (k % 2) * m : coord(rng));
    h.push_back(height(rng));
  }
  for (const ps::core::Chart* chart : {static_cast<const ps::core::Chart*>(&latlong),
                                       static_cast<const ps::core::Chart*>(&flat)}) {
    std::vector<double> x(u.size()), y(u.size()), z(u.size());
    chart->scatteredPositions(u.data(), v.data(), h.data(), u.size(),
                              {x.data(), y.data(), z.data()});
    for (std::size_t k = 0; k < u.size(); ++k) {
      const Eigen::Vector3d p = chart->position(u[k], v[k], double(h[k]));
      ASSERT_EQ(Eigen::Vector3d(x[k], y[k], z[k]), p)
          << chart->name() << " vertex (" << u[k] << ", " << v[k] << ")";
    }
  }
}
