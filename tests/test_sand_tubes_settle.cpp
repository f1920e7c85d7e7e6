// The torus's and the cylinder's sand through the edit pipeline: the settler after stamps across
// the seams and rims, random stamps and erosion keeping the volume, a stamp across the seam
// against the same stamp elsewhere (docs/SAND.md, "The torus and the cylinder").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/sand_grid.hpp"
#include "sand/settler.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"

using namespace ps;

namespace {

using sandtest::smallTube;
using sandtest::tubeName;

// Heights of v alone (both surfaces are the same in every column): a ripple along v.
std::vector<float> rowHeights(const core::Chart& chart) {
  const core::GridSize g = chart.grid();
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    const float x = float(20.0 + 8.0 * std::sin(6.0 * std::numbers::pi * v / g.m()));
    for (int u = 0; u <= g.m(); ++u) h[g.index(u, v)] = x;
  }
  if (chart.gluing().vSides == core::SideGluing::kSeam) {
    for (int u = 0; u <= g.m(); ++u) h[g.index(u, g.m())] = h[g.index(u, 0)];
  }
  return h;
}

}  // namespace

TEST(SandTubes, TheSettlerSettlesStampsAcrossTheSeamsKeepingBoundsAndVolume) {
  for (const bool torus : {true, false}) {
    for (const sand::SettleMethod method :
         {sand::SettleMethod::kThermal, sand::SettleMethod::kDiffusionExplicit,
          sand::SettleMethod::kDiffusionSemiImplicit}) {
      auto chart = smallTube(torus, 7);
      const int m = chart->grid().m();
      terrain::Terrain t(chart, rowHeights(*chart));
      edit::EditPipeline pipe(t);
      sand::Settler settler(t, sand::Material::sand(), {.method = method, .cellBudget = 100000});
      sand::DisplacementTool tool(chart, {.radius = 600.0}, &settler);
      const sand::SandGrid grid(chart);
      const double v0 = grid.volume(t.heights());
      pipe.apply(tool, {chart->position(0, 0, 600.0 - 300.0), 0.0});  // a corner, or a rim
      pipe.apply(tool, {chart->position(0, m / 2, 600.0 - 300.0), 0.0});
      pipe.apply(tool, {chart->position(m / 3, m, 600.0 - 300.0), 0.0});
      int frames = 0;
      while (frames < 3000) {
        const sand::FrameReport r = settler.frame();
        ++frames;
        if (r.atRest) break;
      }
      EXPECT_TRUE(settler.atRest()) << tubeName(torus) << " " << int(method);
      EXPECT_GT(frames, 1);
      EXPECT_TRUE(edittest::consistentHeights(t)) << tubeName(torus);
      EXPECT_TRUE(edittest::boundsEqualFullRebuild(t)) << tubeName(torus);
      if (method == sand::SettleMethod::kThermal) {
        EXPECT_LE(sandtest::worstTalusExcess(settler.field(), settler.material()),
                  settler.material().talusTolerance * (1 + 1e-9));
      }
      const double drift = std::abs(grid.volume(t.heights()) - v0) / grid.absVolume(t.heights());
      EXPECT_LE(drift, 1e-9) << tubeName(torus) << " " << int(method);
      std::printf("%s, %s: settled in %d frames, float volume drift %.3g\n", tubeName(torus),
                  sand::toString(method).c_str(), frames, drift);
      const auto revision = t.revision();
      EXPECT_EQ(settler.frame().cellSteps, 0u);
      EXPECT_EQ(t.revision(), revision);
    }
  }
}

TEST(SandTubes, RandomStampsAndErosionKeepTheVolume) {
  // Random stamps anywhere (a third on or beside the seams and rims), each followed by a few
  // settler frames of thermal erosion: the floats' volume sum_i A_i h_i stays the first one.
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 7);
    const int m = chart->grid().m();
    terrain::Terrain t(chart, rowHeights(*chart));
    edit::EditPipeline pipe(t);
    pipe.setUndoEnabled(false);
    sand::Settler settler(t, sand::Material::sand(), {.cellBudget = 20000});
    const sand::SandGrid grid(chart);
    const double v0 = grid.volume(t.heights()), scale = grid.absVolume(t.heights());
    std::mt19937 rng(torus ? 21 : 22);
    std::uniform_int_distribution<int> any(0, m), near(-2, 2);
    // Pressed 30-150 m: the ramparts stay below the height limit (375 m on the torus), where
    // clamping would lose volume by design.
    std::uniform_real_distribution<double> radius(300.0, 900.0), press(30.0, 150.0);
    double worst = 0;
    for (int i = 0; i < 60; ++i) {
      core::GridPoint p{any(rng), any(rng)};
      if (i % 3 == 0) p.u = (near(rng) + m) % m;
      if (i % 3 == 1) p.v = torus ? (near(rng) + m) % m : std::clamp(near(rng), 0, m);
      const double r = radius(rng);
      sand::DisplacementTool tool(chart, {.radius = r}, &settler);
      pipe.apply(tool, {chart->position(p.u, p.v, r - press(rng)), 0.0});
      for (int f = 0; f < 3; ++f) settler.frame();
      worst = std::max(worst, std::abs(grid.volume(t.heights()) - v0) / scale);
      ASSERT_LE(worst, 1e-9) << tubeName(torus) << " stamp " << i;
    }
    EXPECT_TRUE(edittest::consistentHeights(t));
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
    std::printf("%s: 60 random stamps with erosion, volume drift at most %.3g\n", tubeName(torus),
                worst);
  }
}

TEST(SandTubes, AStampAcrossTheSeamEqualsTheSameStampAwayFromIt) {
  // Both surfaces are the same in every column, so a stamp on the u seam, settled, is the same
  // stamp half-way round with the grid shifted by m/2 columns (to rounding: the columns'
  // sines and cosines are not shifted bit for bit).
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 7);
    const int m = chart->grid().m();
    const core::GridSize g = chart->grid();
    const int v = torus ? m / 8 : m / 2;
    auto stampAt = [&](int u) {
      terrain::Terrain t(chart, rowHeights(*chart));
      edit::EditPipeline pipe(t);
      sand::Settler settler(t, sand::Material::sand(), {.cellBudget = 1000000});
      sand::DisplacementTool tool(chart, {.radius = 700.0}, &settler);
      pipe.apply(tool, {chart->position(u, v, 700.0 - 300.0), 0.0});
      for (int f = 0; f < 400 && !settler.atRest(); ++f) settler.frame();
      EXPECT_TRUE(settler.atRest());
      return std::vector<float>(t.heights().begin(), t.heights().end());
    };
    const auto seam = stampAt(0), away = stampAt(m / 2);
    const auto flat = rowHeights(*chart);
    double worst = 0, depth = 0;
    for (int vv = 0; vv <= m; ++vv) {
      for (int u = 0; u <= m; ++u) {
        const float a = seam[g.index(u, vv)], b = away[g.index((u + m / 2) % m, vv)];
        worst = std::max(worst, double(std::abs(a - b)));
        depth = std::max(depth, double(std::abs(a - flat[g.index(u, vv)])));
      }
    }
    EXPECT_GT(depth, 100.0) << tubeName(torus);
    EXPECT_LE(worst, 1e-4 * depth) << tubeName(torus);
    std::printf(
        "%s: a stamp on the seam against the same stamp shifted by m/2: %.3g m apart "
        "(%.0f m deep)\n",
        tubeName(torus), worst, depth);
  }
}

TEST(SandTubes, TheSettlerIsToldOfEveryVertexAStampChanges) {
  // The settler marks what the tool reports: on the torus the dirty box is the centre's half in v,
  // so a stamp across the inner equator's midline (v = m/2) or the v seam changes vertices
  // outside it, in its images, which the listener must be told of as well.
  struct Recorder : sand::EditListener {
    std::vector<terrain::VertexBox> told;
    void edited(const terrain::VertexBox& r, const sand::Material&) override { told.push_back(r); }
  };
  for (const bool torus : {true, false}) {
    auto chart = smallTube(torus, 7);
    const int m = chart->grid().m();
    const core::GridSize g = chart->grid();
    for (const core::GridPoint p :
         {core::GridPoint{5, m / 2 + 1}, core::GridPoint{m / 3, 1}, core::GridPoint{0, m - 1}}) {
      terrain::Terrain t(chart, rowHeights(*chart));
      const std::vector<float> before(t.heights().begin(), t.heights().end());
      edit::EditPipeline pipe(t);
      Recorder rec;
      sand::DisplacementTool tool(chart, {.radius = 900.0}, &rec);
      pipe.apply(tool, {chart->position(p.u, p.v, 900.0 - 150.0), 0.0});
      auto told = [&](int u, int v) {
        for (const terrain::VertexBox& r : rec.told) {
          if (v < r.vBegin || v > r.vEnd) continue;
          for (int k = -1; k <= 1; ++k) {
            if (u + k * m >= r.uBegin && u + k * m <= r.uEnd) return true;
          }
        }
        return false;
      };
      int changed = 0;
      for (int v = 0; v <= m; ++v) {
        for (int u = 0; u <= m; ++u) {
          if (t.heights()[g.index(u, v)] == before[g.index(u, v)]) continue;
          ++changed;
          const core::GridPoint c = chart->canonical(u, v);
          EXPECT_TRUE(told(u, v) || told(c.u, c.v))
              << tubeName(torus) << " stamp " << p.u << "," << p.v << ": " << u << "," << v;
        }
      }
      EXPECT_GT(changed, 20) << tubeName(torus);
    }
  }
}
