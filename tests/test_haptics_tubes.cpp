// The haptic force path on the torus and the cylinder: the snapshot reaches across the seams (the
// torus's v seam too), and presses across them displace sand with its volume kept
// (docs/HAPTICS.md).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

#include "core/cylinder_chart.hpp"
#include "core/torus_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "haptics/force_log.hpp"
#include "haptics/force_path.hpp"
#include "haptics/terrain_patch.hpp"
#include "sand/sand_grid.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_haptics_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using namespace ps::haptics;

namespace {

// The default torus and cylinder of the AR scene (app/default_planet.hpp).
std::shared_ptr<const core::Chart> sceneTube(bool torus, int n) {
  if (torus) return std::make_shared<core::TorusChart>(core::GridSize(n), 4.5e6, 1.8e6);
  return std::make_shared<core::CylinderChart>(core::GridSize(n), 6e6, 4e6);
}

// The full terrain's bilinear height at grid coordinates (u, v), wrapped across the seams.
double fullHeight(const terrain::Terrain& t, double u, double v) {
  const int m = t.grid().m();
  const bool wrapsV = t.chart().gluing().vSides == core::SideGluing::kSeam;
  const int iu = int(std::floor(u)), iv = std::min(int(std::floor(v)), wrapsV ? m : m - 1);
  const double a = u - iu, b = v - iv;
  auto h = [&](int uu, int vv) {
    uu = ((uu % m) + m) % m;
    if (wrapsV) vv = ((vv % m) + m) % m;
    return double(t.height(uu, vv));
  };
  return (1 - b) * ((1 - a) * h(iu, iv) + a * h(iu + 1, iv)) +
         b * ((1 - a) * h(iu, iv + 1) + a * h(iu + 1, iv + 1));
}

}  // namespace

TEST(HapticsPatch, TorusAndCylinderPatchesReachAcrossTheSeams) {
  // A tool over the torus's corner (both seams), its outer equator (the v seam) and its u seam,
  // over the cylinder's seam and beside a rim: a ring of points 4 largest cells about it is in the
  // patch, at the full terrain's depth.
  for (const bool torus : {true, false}) {
    auto chart = sceneTube(torus, 7);
    const terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 4, 20e3));
    const int m = t.grid().m();
    const double cell = 2.0 * std::numbers::pi * (torus ? 6.3e6 : 6e6) / m;
    const std::vector<core::GridPoint> at =
        torus ? std::vector<core::GridPoint>{{0, 0}, {m / 3, 0}, {0, m / 3}, {m / 5, m / 2}}
              : std::vector<core::GridPoint>{{0, m / 2}, {m / 3, 2}, {0, m - 2}};
    for (const core::GridPoint p : at) {
      const Eigen::Vector3d c = chart->position(p.u, p.v, 0.0), up = chart->up(p.u, p.v);
      TerrainPatch patch;
      ASSERT_TRUE(patch.capture(t, c, 4));
      const Eigen::Vector3d e1 = up.unitOrthogonal(), e2 = up.cross(e1);
      for (int k = 0; k < 16; ++k) {
        const double phi = 2 * std::numbers::pi * k / 16;
        const Eigen::Vector3d q =
            c + 3.0 * cell * (std::cos(phi) * e1 + std::sin(phi) * e2) + 100.0 * up;
        const auto uv = chart->inverse(q);
        ASSERT_TRUE(uv);
        if (!torus && ((*uv)(1) <= 0.0 || (*uv)(1) >= m)) continue;  // beyond a rim
        const auto s = patch.probe(q);
        ASSERT_TRUE(s) << (torus ? "torus " : "cylinder ") << p.u << "," << p.v << " k " << k;
        EXPECT_NEAR(*patch.heightAt((*uv)(0), (*uv)(1)), fullHeight(t, (*uv)(0), (*uv)(1)), 1e-3)
            << p.u << "," << p.v << " k " << k;
      }
    }
  }
}

TEST(HapticsForcePath, PressesAcrossTheTorussSeams) {
  // A stroke pushed in at the torus's corner and dragged along its outer equator across the u
  // seam and back over the v seam: forces felt, sand displaced on both sides of each seam, the
  // volume kept, twins one height, the same log and planet twice.
  auto chart = sceneTube(true, 9);  // cells of 77 km (u, outer equator) and 22 km (v)
  const int m = chart->grid().m();
  const double scale = 6.3e6 / 0.06;  // the bounding sphere on a 6 cm globe
  auto run = [&] {
    return haptictest::pressDragLift(chart, 20e3f, scale, [&](double alt, double x) {
      // From (-4, -3) cells to (+4, +3) cells about the corner: across both seams.
      const double u = 4.0 * x, v = 3.0 * x;
      const double uu = u < 0 ? u + m : u, vv = v < 0 ? v + m : v;
      return chart->positionAt(uu, vv, 20e3 + alt);
    });
  };
  const haptictest::StrokeOutcome a = run();
  EXPECT_GT(a.touching, 1000);
  EXPECT_EQ(a.faults, 0);
  EXPECT_GT(a.maxForce, 1.0);
  EXPECT_LT(a.volumeDrift, 1e-9);
  const core::GridSize g = chart->grid();
  auto changed = [&](int u, int v) { return a.heights[g.index(u, v)] != 20e3f; };
  EXPECT_TRUE(changed(2, 2));          // beyond both seams
  EXPECT_TRUE(changed(m - 2, m - 2));  // before them
  const haptictest::StrokeOutcome b = run();
  EXPECT_EQ(a.log, b.log);
  EXPECT_EQ(a.heights, b.heights);
}
