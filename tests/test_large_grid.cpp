// The paper's largest planet, 8193^2 (67 M vertices): the same invariants as on small grids,
// checked on views that reach the finest level, so nothing only works while a grid is small.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mesh_checks.hpp"
#include "stress_util.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

// Cheap rough relief (a few trig terms of the direction) so building 67 M heights stays quick.
terrain::Terrain largeTerrain(int n) {
  auto chart = testkit::earthChart(n);
  const core::GridSize g = chart->grid();
  std::vector<float> h(g.count());
#pragma omp parallel for schedule(static)
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const Eigen::Vector3d d = chart->direction(u, v);
      const double x = 3000 * std::sin(40 * d.x() + 1) * std::cos(37 * d.y()) +
                       1500 * std::sin(301 * d.z() + 5 * d.x()) +
                       400 * std::sin(2300 * d.x()) * std::sin(2100 * d.y() + 1);
      h[g.index(u, v)] = float(x);
    }
  }
  return terrain::Terrain(chart, std::move(h));
}

}  // namespace

// Under the sanitizers the grid is 4097^2 (a quarter of the vertices: the same levels but the
// last, in a quarter of the time); the optimised pass checks the paper's 8193^2.
TEST(LargeGrid, Grid8193ViewsAreCrackFreeAndWithinDistMax) {
  const int n = testkit::underAsan() ? 12 : 13;
  const auto t = largeTerrain(n);
  ASSERT_EQ(t.grid().side(), (1 << n) + 1);
  if (n == 13) {
    // Heights + bounds, 8 bytes per vertex, and the tessellator's packed copy of every 8th row
    // and column (12 bytes per lattice vertex: height, codes and the children's largest error;
    // level by level: the four grid corners are not stored and each even row of an edge level
    // leaves one entry unused, 1,033 in all): within 600 MB.
    static_assert(sizeof(terrain::LatticeEntry) == 12);
    EXPECT_EQ(t.bytes(), std::size_t(8193) * 8193 * 8 + (std::size_t(1025) * 1025 + 1029) * 12);
    EXPECT_LE(t.bytes(), 600'000'000u);
  }
  const int m = t.grid().m();
  const double R = testkit::kEarthRadius;
  // Close to the surface over the seam and over the north pole, and from orbit.
  const Eigen::Vector3d seamGround = t.chart().position(0, m / 2 + 100, t.height(0, m / 2 + 100));
  const Eigen::Vector3d poleGround = t.chart().position(0, m - 3, t.height(0, m - 3));
  const std::vector<terrain::Camera> views = {
      terrain::Camera::lookAt(seamGround * (1 + 2000.0 / R),
                              seamGround + Eigen::Vector3d(0, 30000, -5000),
                              seamGround.normalized(), 640, 480, 1.2),
      terrain::Camera::lookAt(poleGround * (1 + 5000.0 / R), Eigen::Vector3d(0, 0, R),
                              Eigen::Vector3d(1, 0, 0), 640, 480, 1.4),
      terrain::Camera::lookAt({0, -3 * R, 0}, {0, 0, 0}, {0, 0, 1}, 640, 480, 0.9)};
  terrain::Tessellator tess;
  for (std::size_t i = 0; i < views.size(); ++i) {
    terrain::TessellationSettings s;
    s.triangleBudget = 0;
    s.distMaxPx = 2.0;
    const auto& mesh = tess.tessellate(t, views[i], s);
    const auto rep = terrain::measureScreenError(t, views[i], mesh);
    EXPECT_LE(rep.maxPx, s.distMaxPx) << "view " << i;
    EXPECT_GT(rep.verticesChecked, 1000u) << "view " << i;
    // Whole planet, nothing culled: conforming everywhere, seam and poles included.
    s.cull = false;
    s.distMaxPx = 8.0;
    EXPECT_EQ(testkit::conformityDefect(t, tess.tessellate(t, views[i], s)), "") << "view " << i;
  }
}
