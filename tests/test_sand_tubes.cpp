// The grid sand core on the torus and the cylinder: cells, areas and links across the seams, the
// cylinder's rims as closed walls, thermal erosion, explicit diffusion and the push force,
// displacement and the settler (docs/SAND.md, "The torus and the cylinder").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numbers>
#include <random>
#include <utility>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/sand_field.hpp"
#include "sand/sand_grid.hpp"
#include "sand/settler.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_explicit_reference.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

constexpr double kPi = std::numbers::pi;

using sandtest::smallTube;
using sandtest::tubeName;

double exactArea(bool torus) {
  return torus ? 4 * kPi * kPi * 4000.0 * 1500.0 : 2 * kPi * 2000.0 * 8000.0;
}

// Heights from a function of a vertex's reference position: twins get one height.
std::vector<float> heightsOfPoint(const core::Chart& chart,
                                  const std::function<double(const Eigen::Vector3d&)>& f) {
  const core::GridSize g = chart.grid();
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) h[g.index(u, v)] = float(f(chart.position(u, v, 0.0)));
  }
  return h;
}

// A pile (height > 0) or a crater (< 0) with vertical walls: `height` within 450 m of the
// spot's point, 0 elsewhere.
std::vector<float> columnOn(const core::Chart& chart, core::GridPoint spot, double height) {
  const Eigen::Vector3d c = chart.position(spot.u, spot.v, 0.0);
  return heightsOfPoint(
      chart, [&](const Eigen::Vector3d& p) { return (p - c).norm() < 450.0 ? height : 0.0; });
}

// Where the tests put piles and stamps: the torus's corner (both seams), its u seam, its v seam
// (the outer equator), its inner equator, its top; the cylinder's seam, both rims (one on the
// seam), its middle.
std::vector<core::GridPoint> spots(bool torus, int m) {
  if (torus) return {{0, 0}, {0, m / 3}, {m / 3, 0}, {m / 5, m / 2}, {m - 3, m / 4}};
  return {{0, m / 2}, {m / 3, 0}, {0, m}, {m / 2, m / 2}, {m - 2, 3}};
}

}  // namespace

TEST(SandTubes, CellAreasSumToTheSurfaceAndLinksAreSymmetric) {
  for (const bool torus : {true, false}) {
    for (int n : {5, 6, 8}) {
      auto chart = smallTube(torus, n);
      const sand::SandGrid g(chart);
      const int m = g.m();
      ASSERT_TRUE(g.glued());
      ASSERT_TRUE(g.tube());
      EXPECT_FALSE(g.sphere());
      sand::CompensatedSum total;
      int cells = 0;
      for (int v = 0; v <= m; ++v) {
        for (int u = 0; u <= m; ++u) {
          const core::GridPoint c = chart->canonical(u, v);
          EXPECT_EQ(g.cellArea(u, v), g.cellArea(c.u, c.v));
          if (!g.isCell(u, v)) continue;
          ASSERT_GT(g.cellArea(u, v), 0.0);
          total.add(g.cellArea(u, v));
          ++cells;
        }
      }
      EXPECT_EQ(cells, torus ? m * m : m * (m + 1)) << tubeName(torus);  // the distinct points
      const double rel = total.value() / exactArea(torus) - 1;
      EXPECT_LE(std::abs(rel), 1e-12) << tubeName(torus) << " n " << n;
      EXPECT_LE(std::abs(g.surfaceArea() / exactArea(torus) - 1), 1e-15);
      std::printf("%s %d: %d cells, area sum / exact - 1 = %.3g\n", tubeName(torus), n, cells, rel);
      EXPECT_NEAR(g.volume(std::vector<float>(g.grid().count(), 2.0f)) / (2 * exactArea(torus)),
                  1.0, 1e-12);
      if (n > 6) continue;
      // Links: i -> j as often as j -> i, with bitwise the same chords and faces; none across a
      // cylinder's rim (5 links on a rim cell), 8 everywhere else.
      ASSERT_NO_FATAL_FAILURE(sandtest::checkLinksSymmetric(
          g, 2.0 * sand::largestSpacing(*chart),
          [&](int, int v) { return !torus && (v == 0 || v == m) ? 5 : 8; }, tubeName(torus)));
    }
  }
}

TEST(SandTubes, ThermalKeepsVolumeAndTheActiveSetStepEqualsTheWholeGridStep) {
  const sand::Material mat = sand::Material::sand();
  sandtest::SettleFigures figures;
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 6);
    const int m = chart->grid().m();
    const auto where = spots(torus, m);
    for (std::size_t s = 0; s < where.size(); ++s) {
      auto h = columnOn(*chart, where[s], s % 2 ? 300.0 : -300.0);
      const std::string what = std::string(tubeName(torus)) + " spot " + std::to_string(s);
      // The pile or crater spread across the seams: beside every twin, inside the grid, some
      // neighbour moved (the steep links are those round the tube, the shorter ones).
      auto movedBesideTwins = [&](const sand::SandField& a) {
        core::GridPoint tw[4];
        const int nt = chart->twins(where[s].u, where[s].v, tw);
        for (int k = 0; k < nt; ++k) {
          int moved = 0;
          for (int dv = -1; dv <= 1; ++dv) {
            for (int du = -1; du <= 1; ++du) {
              const int u = tw[k].u + du, v = tw[k].v + dv;
              if (u < 0 || u > m || v < 0 || v > m || (du == 0 && dv == 0)) continue;
              moved += a.height(u, v) != 0.0;
            }
          }
          EXPECT_GT(moved, 0) << what << " (" << tw[k].u << "," << tw[k].v << ")";
        }
      };
      ASSERT_NO_FATAL_FAILURE(sandtest::settlePile(chart, h, mat, what, figures, movedBesideTwins));
      EXPECT_TRUE(edittest::consistentHeights(terrain::Terrain(chart, h)));
    }
  }
  std::printf(
      "thermal, 10 piles and craters settled (at most %d steps): volume drift at most %.3g\n",
      figures.mostSteps, figures.worstDrift);
}

TEST(SandTubes, ThermalStepsEqualACellByCellReferenceBitForBit) {
  // 129^2: border tiles (by the seams and rims) and inner tiles (one pass from shared chords);
  // cells ~200 m and ~100 m, noise of 300 m.
  for (const bool torus : {true, false}) {
    ASSERT_NO_FATAL_FAILURE(sandtest::checkThermalAgainstReference(smallTube(torus, 7), {31, 64},
                                                                   300.0, 6, tubeName(torus)));
  }
}

TEST(SandTubes, ExplicitStepsEqualACellByCellReferenceBitForBit) {
  // 129^2 (tiles weighed once face by face and tiles by the seams and rims); noise of 300 m.
  for (const bool torus : {true, false}) {
    ASSERT_NO_FATAL_FAILURE(sandtest::checkExplicitAgainstReference(smallTube(torus, 7), {31, 64},
                                                                    300.0, 6, tubeName(torus)));
  }
}

TEST(SandTubes, ExplicitDiffusionKeepsVolumeAndTheActiveSetStepEqualsTheWholeGridStep) {
  const sand::Material mat = sand::Material::sand();
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 6);
    const int m = chart->grid().m();
    const auto where = spots(torus, m);
    for (std::size_t s = 0; s < where.size(); ++s) {
      auto h = columnOn(*chart, where[s], -300.0);
      ASSERT_NO_FATAL_FAILURE(sandtest::explicitCraterDiffuses(
          chart, h, mat, std::string(tubeName(torus)) + " spot " + std::to_string(s)));
    }
    // Past the bound: refused.
    std::vector<float> ones(chart->grid().count(), 1.0f);
    sand::SandField f(chart, ones);
    sandtest::refusesTwiceTheExplicitBound(f, mat);
  }
}

TEST(SandTubes, APushForceAcrossTheSeamKeepsVolumeAndTouchesNothingAcrossTheTube) {
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 6);
    const int m = chart->grid().m();
    const core::GridPoint p = torus ? core::GridPoint{0, 0} : core::GridPoint{0, m / 2};
    sandtest::pushTheLayer(chart, {.at = p, .radius = 1200.0}, tubeName(torus),
                           [&](const sand::SandField& a, const sand::SandField& b) {
                             // Both sides of the u seam moved (and of the torus's v seam).
                             EXPECT_NE(a.height(2, p.v), 10.0);
                             EXPECT_NE(a.height(m - 2, p.v), 10.0);
                             if (torus) {
                               EXPECT_NE(a.height(0, 2), 10.0);
                               EXPECT_NE(a.height(0, m - 2), 10.0);
                             }
                             // The far side of the tube and, on the torus, the inner equator across
                             // the hole: untouched.
                             EXPECT_EQ(b.height(m / 2, p.v), 10.0);
                             if (torus) {
                               EXPECT_EQ(b.height(0, m / 2), 10.0);
                             }
                           });
  }
}

TEST(SandTubes, DisplacementAtTheSeamsAndRimsKeepsTheVolumeAndUndoes) {
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 7);  // cells of 98-258 m (torus), 98 / 62 m (cylinder)
    const int m = chart->grid().m();
    terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 3, 20.0));
    edit::EditPipeline pipe(t);
    pipe.setUndoEnabled(false);
    sand::DisplacementTool tool(chart, {.radius = 600.0});
    const sand::SandGrid grid(chart);
    auto where = spots(torus, m);
    std::mt19937 rng(torus ? 11 : 12);
    std::uniform_int_distribution<int> any(0, m), near(-3, 3);
    for (int i = 0; i < 24; ++i) {  // near the seams (and rims), then anywhere
      const int a = any(rng), d = near(rng);
      where.push_back(i % 3 == 0   ? core::GridPoint{(d + m) % m, a}
                      : i % 3 == 1 ? core::GridPoint{a, std::clamp(torus ? (d + m) % m : d, 0, m)}
                                   : core::GridPoint{a, any(rng)});
    }
    double worst = 0, worstOfRemoved = 0;
    for (const core::GridPoint p : where) {
      const double vBefore = grid.volume(t.heights());
      // 120 m deep: the rampart stays below the height limit (a quarter of the tube's radius),
      // where clamping would lose volume by design.
      pipe.apply(tool, {chart->position(p.u, p.v, 600.0 - 120.0), 0.0});
      const sand::DisplacementStats& s = tool.lastStats();
      ASSERT_GT(s.removedVolume, 1e5) << tubeName(torus) << " " << p.u << "," << p.v;
      EXPECT_NEAR(s.depositedVolume, s.removedVolume, 1e-12 * s.removedVolume);
      const double dv = grid.volume(t.heights()) - vBefore;
      EXPECT_NEAR(dv, s.floatVolumeChange, 1e-9 * s.removedVolume) << p.u << "," << p.v;
      // What is left is one vertex's rounding to float (the rest is carried): of a cell of about
      // 2e4 m^2 at 20-200 m, a few tenths of a cubic metre.
      EXPECT_LE(std::abs(dv), 1e-7 * s.removedVolume) << p.u << "," << p.v;
      worst = std::max(worst, std::abs(dv) / grid.absVolume(t.heights()));
      worstOfRemoved = std::max(worstOfRemoved, std::abs(dv) / s.removedVolume);
      ASSERT_TRUE(edittest::consistentHeights(t)) << tubeName(torus) << " " << p.u << "," << p.v;
    }
    EXPECT_LE(worst, 1e-9) << tubeName(torus);
    std::printf(
        "%s: %zu stamps, float volume change at most %.3g of the planet's (sum A |h|), "
        "%.3g of the removed volume\n",
        tubeName(torus), where.size(), worst, worstOfRemoved);
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t)) << tubeName(torus);
    // A tool wider than the tube: refused, naming it.
    sand::DisplacementTool wide(chart, {.radius = torus ? 1600.0 : 2100.0});
    EXPECT_THROW(pipe.apply(wide, {chart->position(0, 0, 0.0), 0.0}), core::InputError);
  }
  // A stamp on the torus's corner changes all four quadrants of the grid; undo restores it.
  auto chart = smallTube(true, 7);
  const int m = chart->grid().m();
  terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 5, 20.0));
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  sand::DisplacementTool tool(chart, {.radius = 600.0});
  pipe.apply(tool, {chart->position(0, 0, 600.0 - 250.0), 0.0});
  const core::GridSize g = t.grid();
  auto changed = [&](int u, int v) { return t.heights()[g.index(u, v)] != before[g.index(u, v)]; };
  EXPECT_TRUE(changed(1, 1));
  EXPECT_TRUE(changed(m - 1, 1));
  EXPECT_TRUE(changed(1, m - 1));
  EXPECT_TRUE(changed(m - 1, m - 1));
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  pipe.undo();
  EXPECT_EQ(std::memcmp(t.heights().data(), before.data(), before.size() * sizeof(float)), 0);
}
