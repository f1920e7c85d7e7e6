// The grid sand core on the octahedral chart (both mappings): cells and links across the folds,
// displacement, thermal erosion and explicit diffusion, the settler (docs/SAND.md, "The
// octahedral chart").
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numbers>
#include <random>
#include <utility>

#include "core/input_error.hpp"
#include "core/octahedral_chart.hpp"
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
using Mapping = core::OctahedralChart::Mapping;

namespace {

using testkit::kOctahedralMappings;

std::shared_ptr<const core::OctahedralChart> octa(int n, double R, Mapping mapping) {
  return std::make_shared<core::OctahedralChart>(core::GridSize(n), R, mapping);
}

const char* nameOf(Mapping m) {
  return m == Mapping::kEqualArea ? "equal area" : "central";
}

// Heights from a function of a vertex's direction: twins get one height.
std::vector<float> heightsOfDirection(const core::Chart& chart,
                                      const std::function<double(const Eigen::Vector3d&)>& f) {
  const core::GridSize g = chart.grid();
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) h[g.index(u, v)] = float(f(chart.up(u, v)));
  }
  return h;
}

// A pile (height > 0) or a crater (< 0) with vertical walls: `height` within 0.16 radians of
// the spot's direction, 0 elsewhere.
std::vector<float> angularColumnOn(const core::Chart& chart, core::GridPoint spot, double height) {
  const Eigen::Vector3d c = chart.up(spot.u, spot.v);
  return heightsOfDirection(
      chart, [&](const Eigen::Vector3d& d) { return (d - c).norm() < 0.16 ? height : 0.0; });
}

// The grid points the tests put piles and stamps on: the south pole (the four corners), a side
// (a fold, south of the equator), a side's midpoint (a cone point, on the equator) on each of
// the two kinds of side, the north pole (the centre), a crease.
std::vector<core::GridPoint> spots(int m) {
  return {{0, 0},     {0, m / 4}, {m / 2, 0},     {0, m / 2},
          {m, m / 2}, {m / 2, m}, {m / 2, m / 2}, {m / 4, m / 4}};
}

}  // namespace

TEST(SandOctahedral, CellAreasSumToTheSphereArePositiveAndLinksAreSymmetric) {
  const double R = 6372790.0;
  for (Mapping mapping : kOctahedralMappings) {
    for (int n : {5, 6, 8}) {
      auto chart = octa(n, R, mapping);
      const sand::SandGrid g(chart);
      const int m = g.m();
      ASSERT_TRUE(g.glued());
      EXPECT_FALSE(g.sphere());
      EXPECT_EQ(g.columns(), m + 1);
      sand::CompensatedSum total;
      int cells = 0;
      double smallest = 1e300, largest = 0;
      for (int v = 0; v <= m; ++v) {
        for (int u = 0; u <= m; ++u) {
          const core::GridPoint c = chart->canonical(u, v);
          EXPECT_EQ(g.cellArea(u, v), g.cellArea(c.u, c.v));
          if (!g.isCell(u, v)) continue;
          const double A = g.cellArea(u, v);
          ASSERT_GT(A, 0.0) << u << "," << v;
          total.add(A);
          ++cells;
          // A cone point (a side's midpoint) owns half a cell: 180 degrees of the square.
          const double full = g.linkCount(u, v) == 4 ? 2 * A : A;
          smallest = std::min(smallest, full);
          largest = std::max(largest, full);
        }
      }
      EXPECT_EQ(cells, m * m + 2);  // the chart's distinct points
      EXPECT_NEAR(total.value() / (4 * std::numbers::pi * R * R), 1.0, 1e-12)
          << nameOf(mapping) << " n " << n;
      std::printf("%s %d: cells %d, area sum / 4 pi R^2 - 1 = %.3g, largest / smallest %.4f\n",
                  nameOf(mapping), n, cells, total.value() / (4 * std::numbers::pi * R * R) - 1,
                  largest / smallest);
      if (mapping == Mapping::kEqualArea) {
        EXPECT_LT(largest / smallest, 1.2) << n;  // measured 1.117: geodesic quads
      } else {
        EXPECT_LT(largest / smallest, 6.0) << n;
      }
      EXPECT_NEAR(
          g.volume(std::vector<float>(g.grid().count(), 2.0f)) / (8 * std::numbers::pi * R * R),
          1.0, 1e-12);
      if (n > 6) continue;
      // Links: i -> j as often as j -> i, with bitwise the same chords and faces; cone points
      // have 4, every other cell 8.
      ASSERT_NO_FATAL_FAILURE(sandtest::checkLinksSymmetric(
          g, 4.0 * 2 * std::numbers::pi * R / m,
          [&](int u, int v) {
            const bool cone =
                (u == m / 2 && (v == 0 || v == m)) || (v == m / 2 && (u == 0 || u == m));
            EXPECT_EQ(g.linkCount(u, v), cone ? 4 : 8);
            return g.linkCount(u, v);
          },
          std::string(nameOf(mapping)) + " n " + std::to_string(n)));
    }
  }
}

TEST(SandOctahedral, ThermalKeepsVolumeAndTheActiveSetStepEqualsTheWholeGridStep) {
  // A 1 km planet on 65^2 (cells ~55 m): a crater or a pile on each spot (a 300 m step: far past
  // the talus), settled from the marked cells only and from the whole grid, step by step.
  const sand::Material mat = sand::Material::sand();
  sandtest::SettleFigures figures;
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(6, 1000.0, mapping);
    const int m = chart->grid().m();
    const auto where = spots(m);
    for (std::size_t s = 0; s < where.size(); ++s) {
      auto h = angularColumnOn(*chart, where[s], s % 2 ? 300.0 : -300.0);
      const std::string what = std::string(nameOf(mapping)) + " spot " + std::to_string(s);
      ASSERT_NO_FATAL_FAILURE(sandtest::settlePile(chart, h, mat, what, figures));
      // Written back: twins hold one float.
      for (int v = 0; v <= m; ++v) {
        for (int u = 0; u <= m; ++u) {
          const core::GridPoint p = chart->canonical(u, v);
          ASSERT_EQ(h[chart->grid().index(u, v)], h[chart->grid().index(p.u, p.v)]);
        }
      }
    }
  }
  std::printf(
      "thermal, 16 piles and craters settled (at most %d steps): volume drift at most %.3g\n",
      figures.mostSteps, figures.worstDrift);
}

TEST(SandOctahedral, ThermalStepsEqualACellByCellReferenceBitForBit) {
  // 129^2: border tiles (by the folds) and inner tiles (stepped in one pass from planes of shared
  // chords) both. A 1 km planet (cells ~28 m), noise of 40 m: slopes far past the talus. The
  // disc straddles a border tile and an inner one.
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(7, 1000.0, mapping);
    ASSERT_NO_FATAL_FAILURE(
        sandtest::checkThermalAgainstReference(chart, {31, 64}, 40.0, 6, nameOf(mapping)));
  }
}

TEST(SandOctahedral, ExplicitStepsEqualACellByCellReferenceBitForBit) {
  // 129^2: tiles whose faces are weighed once (each inner face's planes alike from both cells)
  // and tiles by the folds that are not. A 1 km planet (cells ~28 m), noise of 40 m: every face
  // moves sand. The disc straddles a border tile and an inner one.
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(7, 1000.0, mapping);
    ASSERT_NO_FATAL_FAILURE(
        sandtest::checkExplicitAgainstReference(chart, {31, 64}, 40.0, 6, nameOf(mapping)));
  }
}

TEST(SandOctahedral, ExplicitDiffusionKeepsVolumeAndTheActiveSetStepEqualsTheWholeGridStep) {
  const sand::Material mat = sand::Material::sand();
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(6, 1000.0, mapping);
    const int m = chart->grid().m();
    const auto where = spots(m);
    for (std::size_t s = 0; s < where.size(); ++s) {
      auto h = angularColumnOn(*chart, where[s], -300.0);
      ASSERT_NO_FATAL_FAILURE(sandtest::explicitCraterDiffuses(
          chart, h, mat, std::string(nameOf(mapping)) + " spot " + std::to_string(s)));
    }
    // Past the bound: refused, naming it.
    auto h = heightsOfDirection(
        *chart, [&](const Eigen::Vector3d& d) { return d.z() > 0.9 ? 100.0 : 0.0; });
    sand::SandField f(chart, h);
    const double bound = sandtest::refusesTwiceTheExplicitBound(f, mat);
    // A step past the bound with the default policy (clamp) stays finite and in range.
    for (int step = 0; step < 200; ++step)
      f.diffusionStep(mat, 10 * bound, sand::DiffusionScheme::kExplicit);
    std::vector<double> out;
    f.copyHeights(out);
    for (double x : out) ASSERT_TRUE(x >= 0.0 && x <= 100.0) << x;
  }
}

TEST(SandOctahedral, APushForceAcrossAFoldKeepsVolumeAndTheActiveSetEqualsTheWholeGrid) {
  // Paper 002's drift under a tool on a fold and on the south pole: the rut reaches both sides of
  // the fold, the volume is kept, and stepping the marked tiles equals stepping every tile.
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(6, 1000.0, mapping);
    const int m = chart->grid().m();
    for (const core::GridPoint p : {core::GridPoint{0, m / 4}, core::GridPoint{0, 0}}) {
      const std::string what =
          std::string(nameOf(mapping)) + " " + std::to_string(p.u) + "," + std::to_string(p.v);
      sandtest::pushTheLayer(chart, {.at = p, .radius = 220.0}, what,
                             [&](const sand::SandField& a, const sand::SandField& b) {
                               // Both sides of the fold moved: (1, v) and, across it, (1, m - v)
                               // (at the corner: (1, 0) and (1, m), beside the twins (0, 0) and (0,
                               // m)).
                               EXPECT_NE(a.height(1, p.v), 10.0);
                               EXPECT_NE(a.height(1, m - p.v), 10.0);
                               // The north pole, far away, untouched (before the drift was kept to
                               // the tool's hemisphere, a ghost of the force pushed at its antipode
                               // in whole-grid steps).
                               EXPECT_EQ(b.height(m / 2, m / 2), 10.0);
                               EXPECT_EQ(b.height(3 * m / 4, m / 2), 10.0);
                             });
    }
  }
}

TEST(SandOctahedral, ThreadCountDoesNotChangeTheResult) {
  // 257^2: 81 tiles, enough for the steps to run in parallel; noise steep everywhere.
  auto chart = octa(8, 256 / std::numbers::pi, Mapping::kEqualArea);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(0.0, 30.0);
  const std::vector<float> h = sandtest::twinNoise(*chart, [&] { return noise(rng); });
  const sand::Material mat = sand::Material::sand();
  const int threads = omp_get_max_threads();
  for (const bool thermal : {true, false}) {
    auto h1 = h, h2 = h;
    sand::SandField a(chart, h1), b(chart, h2);
    a.markAll();
    b.markAll();
    const double dt = a.explicitBound(mat);
    auto step = [&](sand::SandField& f) {
      if (thermal) {
        f.thermalStep(mat);
      } else {
        f.diffusionStep(mat, dt, sand::DiffusionScheme::kExplicit);
      }
    };
    omp_set_num_threads(1);
    for (int i = 0; i < 8; ++i) step(a);
    omp_set_num_threads(std::max(2, threads));
    for (int i = 0; i < 8; ++i) step(b);
    omp_set_num_threads(threads);
    std::vector<double> ha, hb;
    a.copyHeights(ha);
    b.copyHeights(hb);
    EXPECT_TRUE(sandtest::sameDoubles(ha, hb)) << (thermal ? "thermal" : "diffusion");
  }
}

TEST(SandOctahedral, MaterialCrossesTheFoldsAndAPileOnAMirrorSettlesSymmetrically) {
  const sand::Material mat = sand::Material::sand();
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(6, 1000.0, mapping);
    const int m = chart->grid().m();
    const core::GridSize g = chart->grid();
    // One tall column on a side's vertex (0, v0): it spreads to both sides of the fold, to
    // (1, v0) and to (1, m - v0) (the grid continued: (-1, v0) is (1, m - v0)).
    for (const core::GridPoint p :
         {core::GridPoint{0, m / 4}, core::GridPoint{m / 4, 0}, core::GridPoint{0, 0}}) {
      auto h = std::vector<float>(g.count(), 0.0f);
      core::GridPoint tw[4];
      const int nt = chart->twins(p.u, p.v, tw);
      for (int k = 0; k < nt; ++k) h[g.index(tw[k].u, tw[k].v)] = 400.0f;
      sand::SandField f(chart, h);
      f.mark({p.u, p.u, p.v, p.v});
      const double v0 = f.volume();
      int steps = 0;
      while (!f.atRest() && steps < 20000) {
        f.thermalStep(mat);
        ++steps;
      }
      EXPECT_TRUE(f.atRest());
      EXPECT_LE(std::abs(f.volume() - v0) / std::abs(v0), 1e-13);
      // Every neighbour of every twin got some: the pile spread across the fold.
      for (int k = 0; k < nt; ++k) {
        for (int dv = -1; dv <= 1; ++dv) {
          for (int du = -1; du <= 1; ++du) {
            const int u = tw[k].u + du, v = tw[k].v + dv;
            if (u < 0 || u > m || v < 0 || v > m || (du == 0 && dv == 0)) continue;
            EXPECT_GT(f.height(u, v), 1.0) << nameOf(mapping) << " (" << u << "," << v << ")";
          }
        }
      }
      EXPECT_LE(sandtest::worstTalusExcess(f, mat), mat.talusTolerance * (1 + 1e-9));
    }
    // A pile centred on a cone point settles into a shape symmetric under the chart's mirror
    // through it (v -> m - v through (0, m/2), the sphere's y -> -y; u -> m - u through
    // (m/2, 0)), up to rounding: the geometry is mirrored to the last bits or so.
    for (const bool flipV : {true, false}) {
      const core::GridPoint p = flipV ? core::GridPoint{0, m / 2} : core::GridPoint{m / 2, 0};
      const Eigen::Vector3d c = chart->up(p.u, p.v);
      auto h = heightsOfDirection(*chart, [&](const Eigen::Vector3d& d) {
        const double r = (d - c).norm();
        return r < 0.2 ? 300.0 * (1.0 - r / 0.2) + 50.0 : 0.0;
      });
      sand::SandField f(chart, h);
      f.markAll();
      int steps = 0;
      while (!f.atRest() && steps < 20000) {
        f.thermalStep(mat);
        ++steps;
      }
      EXPECT_TRUE(f.atRest());
      double worst = 0;
      for (int v = 0; v <= m; ++v) {
        for (int u = 0; u <= m; ++u) {
          const double a = f.height(u, v);
          const double b = flipV ? f.height(u, m - v) : f.height(m - u, v);
          worst = std::max(worst, std::abs(a - b));
        }
      }
      EXPECT_LE(worst, 1e-6 * 350.0) << nameOf(mapping) << (flipV ? " v flip" : " u flip");
    }
  }
}

TEST(SandOctahedral, DisplacementKeepsTheVolumeAtTheFoldsCornersAndConePoints) {
  // A 20 km planet on 129^2 (cells ~0.5 km), stamps of 4 km pressed 1.5 km deep on the spots
  // and at 24 random places within 6 cells of a side.
  for (Mapping mapping : kOctahedralMappings) {
    auto chart = octa(7, 20e3, mapping);
    const int m = chart->grid().m();
    terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 3, 100.0));
    edit::EditPipeline pipe(t);
    pipe.setUndoEnabled(false);
    sand::DisplacementTool tool(chart, {.radius = 4000.0});
    const sand::SandGrid grid(chart);
    auto where = spots(m);
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> side(0, 3), along(0, m), in(0, 6);
    for (int i = 0; i < 24; ++i) {
      const int a = along(rng), d = in(rng);
      const int s = side(rng);
      where.push_back(s == 0   ? core::GridPoint{d, a}
                      : s == 1 ? core::GridPoint{m - d, a}
                      : s == 2 ? core::GridPoint{a, d}
                               : core::GridPoint{a, m - d});
    }
    double worst = 0;
    for (const core::GridPoint p : where) {
      const double vBefore = grid.volume(t.heights());
      pipe.apply(tool, {chart->position(p.u, p.v, 4000.0 - 1500.0), 0.0});
      const sand::DisplacementStats& s = tool.lastStats();
      ASSERT_GT(s.removedVolume, 1e9) << p.u << "," << p.v;
      EXPECT_NEAR(s.depositedVolume, s.removedVolume, 1e-12 * s.removedVolume);
      const double dv = grid.volume(t.heights()) - vBefore;
      EXPECT_NEAR(dv, s.floatVolumeChange, 1e-9 * s.removedVolume) << p.u << "," << p.v;
      worst = std::max(worst, std::abs(dv) / s.removedVolume);
      ASSERT_TRUE(edittest::consistentHeights(t)) << p.u << "," << p.v;
    }
    EXPECT_LE(worst, 1e-9) << nameOf(mapping);
    std::printf("%s: %zu stamps, float volume change at most %.3g of the removed volume\n",
                nameOf(mapping), where.size(), worst);
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  }
  // A stamp on a fold changes both sides of it, and undo restores it bit for bit.
  auto chart = octa(7, 20e3, Mapping::kEqualArea);
  const int m = chart->grid().m();
  terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 5, 100.0));
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  sand::DisplacementTool tool(chart, {.radius = 3000.0, .rampartWidth = 1.5});
  pipe.apply(tool, {chart->position(0, m / 4, 3000.0 - 1200.0), 0.0});
  const core::GridSize g = t.grid();
  auto changed = [&](int u, int v) { return t.heights()[g.index(u, v)] != before[g.index(u, v)]; };
  EXPECT_TRUE(changed(2, m / 4));
  EXPECT_TRUE(changed(2, m - m / 4));  // across the fold
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  pipe.undo();
  EXPECT_EQ(std::memcmp(t.heights().data(), before.data(), before.size() * sizeof(float)), 0);
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}

TEST(SandOctahedral, TheSettlerSettlesCratersAcrossTheFoldsKeepingBoundsAndVolume) {
  for (const sand::SettleMethod method :
       {sand::SettleMethod::kThermal, sand::SettleMethod::kDiffusionExplicit,
        sand::SettleMethod::kDiffusionSemiImplicit}) {
    auto chart = octa(7, 20e3, Mapping::kEqualArea);
    const int m = chart->grid().m();
    terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 7, 100.0));
    edit::EditPipeline pipe(t);
    sand::Settler settler(t, sand::Material::sand(), {.method = method, .cellBudget = 100000});
    sand::DisplacementTool tool(chart, {.radius = 4000.0}, &settler);
    const sand::SandGrid grid(chart);
    const double v0 = grid.volume(t.heights());
    pipe.apply(tool, {chart->position(0, 0, 4000.0 - 2000.0), 0.0});      // the south pole
    pipe.apply(tool, {chart->position(m / 2, 0, 4000.0 - 2000.0), 0.0});  // a cone point
    pipe.apply(tool, {chart->position(0, m / 3, 4000.0 - 2000.0), 0.0});  // a fold
    int frames = 0;
    while (frames < 3000) {
      const sand::FrameReport r = settler.frame();
      ++frames;
      if (r.atRest) break;
    }
    EXPECT_TRUE(settler.atRest()) << int(method);
    EXPECT_GT(frames, 1);
    EXPECT_TRUE(edittest::consistentHeights(t));
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
    if (method == sand::SettleMethod::kThermal) {
      EXPECT_LE(sandtest::worstTalusExcess(settler.field(), settler.material()),
                settler.material().talusTolerance * (1 + 1e-9));
    }
    EXPECT_LE(std::abs(grid.volume(t.heights()) - v0) / grid.absVolume(t.heights()), 1e-6);
    const auto revision = t.revision();
    EXPECT_EQ(settler.frame().cellSteps, 0u);
    EXPECT_EQ(t.revision(), revision);
  }
}
