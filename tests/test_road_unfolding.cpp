// A road across the glued sides of a planet's grid (io/road_unfolding.hpp): the plane's moves that
// the gluing makes are symmetries of the surface, the sides' great circles are found, and cutting
// a road along a line keeps its area and leaves every piece on one side.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "io/road_unfolding.hpp"

using namespace ps;

TEST(RoadUnfolding, EveryGluingMoveIsASymmetryOfTheSurface) {
  const core::OctahedralChart octa(core::GridSize(6), 1000.0);
  const core::LatLongChart latlong(core::GridSize(6), 1000.0);
  std::mt19937 rng(7);
  for (const core::Chart* chart :
       {static_cast<const core::Chart*>(&octa), static_cast<const core::Chart*>(&latlong)}) {
    const double m = chart->grid().m();
    const auto moves = io::gluingMoves(*chart, m);
    ASSERT_EQ(moves.front(), io::PlaneMove{});
    EXPECT_GT(moves.size(), 4u) << chart->name();
    std::uniform_real_distribution<double> in(0.0, m);
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector2d p(in(rng), in(rng));
      const Eigen::Vector3d at = chart->positionAt(p.x(), p.y(), 0.0);
      for (const io::PlaneMove& move : moves) {
        // The image, moved back into the grid, is the same point of the surface.
        const Eigen::Vector2d back = io::intoGrid(*chart, m, move(p));
        EXPECT_LT((chart->positionAt(back.x(), back.y(), 0.0) - at).norm(), 1e-9 * 1000.0)
            << chart->name() << " move s=" << move.s << " t=" << move.t.transpose()
            << " p=" << p.transpose();
      }
    }
  }
}

TEST(RoadUnfolding, GluedSidesAreFoundAsGreatCircles) {
  const core::OctahedralChart octa(core::GridSize(6), 1000.0);
  const auto folds = io::gluedSidePlanes(octa, octa.grid().m());
  ASSERT_EQ(folds.size(), 2u);  // the meridians 0/180 (y = 0) and 90/-90 (x = 0)
  for (const Eigen::Vector3d& n : folds) {
    EXPECT_NEAR(n.z(), 0.0, 1e-12);
    EXPECT_NEAR(std::abs(n.x()) + std::abs(n.y()), 1.0, 1e-12);
  }
  const core::LatLongChart latlong(core::GridSize(6), 1000.0);
  const auto seams = io::gluedSidePlanes(latlong, latlong.grid().m());
  ASSERT_EQ(seams.size(), 1u);  // the +-180 degree meridian; the pole rows are no side
  EXPECT_NEAR(std::abs(seams[0].y()), 1.0, 1e-12);
}

TEST(RoadUnfolding, CuttingAlongALineKeepsTheAreaAndSidesThePieces) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    // A strip of 2 x 10 triangles, a random line through its box.
    std::vector<Eigen::Vector3d> v;
    std::vector<std::array<std::uint32_t, 3>> t;
    for (int i = 0; i <= 10; ++i) v.emplace_back(-1, i - 5, 0), v.emplace_back(1, i - 5, 0);
    for (std::uint32_t i = 0; i < 10; ++i)
      t.push_back({2 * i, 2 * i + 1, 2 * i + 3}), t.push_back({2 * i, 2 * i + 3, 2 * i + 2});
    const Eigen::Vector2d n = Eigen::Vector2d(unit(rng), unit(rng)).normalized();
    const double c = 2 * unit(rng);
    const auto f = [&](const Eigen::Vector3d& p) { return n.x() * p.x() + n.y() * p.y() - c; };
    const auto area = [&]() {
      double a = 0;
      for (const auto& tri : t) {
        const Eigen::Vector3d e1 = v[tri[1]] - v[tri[0]], e2 = v[tri[2]] - v[tri[0]];
        a += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
      }
      return a;
    };
    const double before = area();
    const std::size_t vertices = v.size();
    io::cutRoadAlong(v, t, f);
    EXPECT_NEAR(area(), before, 1e-9);
    for (const auto& tri : t) {
      const double a = f(v[tri[0]]), b = f(v[tri[1]]), d = f(v[tri[2]]);
      EXPECT_TRUE((a >= -1e-12 && b >= -1e-12 && d >= -1e-12) ||
                  (a <= 1e-12 && b <= 1e-12 && d <= 1e-12))
          << "a piece on both sides, trial " << trial;
    }
    // Each cut edge got one point, on the line.
    for (std::size_t k = vertices; k < v.size(); ++k) EXPECT_NEAR(f(v[k]), 0.0, 1e-12);
  }
}
