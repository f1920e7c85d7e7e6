#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "core/input_error.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/settler.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using sandtest::flatChart;
using sandtest::heightsFrom;
using sandtest::sphereChart;

namespace {

using edittest::pointAbove;

bool sameFloats(std::span<const float> a, std::span<const float> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The float heights are symmetric under the 8 symmetries of the square about (c, c), to
// `ulps` float steps: heights are rounded to float with the volume each rounding loses carried
// to the next vertex (error diffusion keeps the volume), so mirror images may round apart by
// one step; a flux that is not symmetric moves them apart by far more.
::testing::AssertionResult symmetric(const terrain::Terrain& t, int c, int ulps = 2) {
  const core::GridSize g = t.grid();
  const int m = g.m();
  auto at = [&](int u, int v) { return t.heights()[g.index(u, v)]; };
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const int du = u - c, dv = v - c;
      const int images[8][2] = {{du, dv}, {-du, dv}, {du, -dv}, {-du, -dv},
                                {dv, du}, {-dv, du}, {dv, -du}, {-dv, -du}};
      for (const auto& im : images) {
        const int uu = c + im[0], vv = c + im[1];
        if (uu < 0 || uu > m || vv < 0 || vv > m) continue;
        const float a = at(u, v), b = at(uu, vv);
        if (std::abs(a - b) > ulps * (std::nextafter(std::max(std::abs(a), std::abs(b)), INFINITY) -
                                      std::max(std::abs(a), std::abs(b)))) {
          return ::testing::AssertionFailure()
                 << "(" << u << "," << v << ") = " << at(u, v) << " but (" << uu << "," << vv
                 << ") = " << at(uu, vv);
        }
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Frames until rest (at most maxFrames); returns the frame count.
int settleFrames(sand::Settler& s, int maxFrames, std::size_t budget,
                 std::size_t* worstOver = nullptr) {
  int frames = 0;
  while (frames < maxFrames) {
    const sand::FrameReport r = s.frame();
    ++frames;
    if (worstOver && r.steps > 1 && r.cellSteps > budget)
      *worstOver = std::max(*worstOver, r.cellSteps - budget);
    if (r.atRest) break;
  }
  return frames;
}

}  // namespace

TEST(SandDisplacement, RemovedVolumeEqualsDepositedVolumeOnFlatAndSphere) {
  // Flat: 1 m cells at 10 m, the sphere pressed 3 m deep.
  {
    auto chart = flatChart(6);
    terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 10.0f));
    edit::EditPipeline pipe(t);
    sand::DisplacementTool tool(chart, {.radius = 5.0});
    const double vBefore = sand::SandGrid(chart).volume(t.heights());
    pipe.apply(tool, {{32.3, 31.8, 10.0 + 5.0 - 3.0}, 0.0});
    const sand::DisplacementStats& s = tool.lastStats();
    EXPECT_GT(s.removedVolume, 10.0);
    EXPECT_NEAR(s.depositedVolume, s.removedVolume, 1e-12 * s.removedVolume);
    EXPECT_NEAR(sand::SandGrid(chart).volume(t.heights()) - vBefore, s.floatVolumeChange, 1e-9);
    // Float rounding only: each changed height moves by at most half an ulp of ~10 m.
    EXPECT_LE(std::abs(s.floatVolumeChange), double(s.lowered + s.raised) * 1e-6);
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  }
  // Sphere (a 20 km planet, ~1 km cells): the equator, the seam, next to a pole, on a pole.
  auto chart = sphereChart(7, 20e3);
  auto t = terrain::Terrain(chart, testkit::bumpyHeights(*chart, 3, 100.0));
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  sand::DisplacementTool tool(chart, {.radius = 4000.0});
  const sand::SandGrid grid(chart);
  for (auto [lat, lon] : {std::pair{0.0, 10.0}, {5.0, 180.0}, {-86.0, 40.0}, {90.0, 0.0}}) {
    const double vBefore = grid.volume(t.heights());
    pipe.apply(tool, {pointAbove(*chart, lat, lon, 4000.0 - 1500.0), 0.0});
    const sand::DisplacementStats& s = tool.lastStats();
    EXPECT_GT(s.removedVolume, 1e9) << lat << " " << lon;
    EXPECT_NEAR(s.depositedVolume, s.removedVolume, 1e-12 * s.removedVolume) << lat << " " << lon;
    const double dv = grid.volume(t.heights()) - vBefore;
    EXPECT_NEAR(dv, s.floatVolumeChange, 1e-9 * s.removedVolume);
    EXPECT_LE(std::abs(dv), 1e-7 * s.removedVolume) << lat << " " << lon;  // float rounding
    EXPECT_TRUE(edittest::consistentHeights(t)) << lat << " " << lon;
  }
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}

TEST(SandDisplacement, FootprintHoldsEveryChangeAndUndoRestoresBitForBit) {
  auto chart = sphereChart(7, 20e3);
  auto t = terrain::Terrain(chart, testkit::bumpyHeights(*chart, 5, 100.0));
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  sand::DisplacementTool tool(chart, {.radius = 3000.0, .rampartWidth = 1.5});
  pipe.apply(tool, {pointAbove(*chart, 30.0, 179.0, 2000.0), 0.0});
  EXPECT_FALSE(sameFloats(t.heights(), before));
  // The journal snapshots footprint() only: undo restores everything only if every change was
  // inside it (the rampart reaches beyond V_d).
  pipe.undo();
  EXPECT_TRUE(sameFloats(t.heights(), before));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}

TEST(SandDisplacement, CentredCraterIsSymmetricAndStaysSoWhileItSettles) {
  auto chart = flatChart(6);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 20.0f));
  edit::EditPipeline pipe(t);
  sand::Settler settler(t, sand::Material::sand(), {.cellBudget = 20000});
  sand::DisplacementTool tool(chart, {.radius = 8.0}, &settler);
  pipe.apply(tool, {{32.0, 32.0, 20.0 + 8.0 - 6.0}, 0.0});
  ASSERT_TRUE(symmetric(t, 32));
  EXPECT_LT(t.height(32, 32), 15.0);
  EXPECT_GT(t.height(32 + 8, 32), 20.0);  // the rampart
  int frames = 0;
  while (frames < 2000) {
    const sand::FrameReport r = settler.frame();
    ++frames;
    ASSERT_TRUE(symmetric(t, 32)) << "frame " << frames;
    if (r.atRest) break;
  }
  EXPECT_TRUE(settler.atRest());
  EXPECT_GT(frames, 2);
  EXPECT_LE(sandtest::worstTalusExcess(settler.field(), settler.material()),
            settler.material().talusTolerance * (1 + 1e-9));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}

TEST(SandDisplacement, DraggingLeavesAFurrowWithRidges) {
  auto chart = flatChart(7);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 10.0f));
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  sand::DisplacementTool tool(chart, {.radius = 6.0, .rampartWidth = 1.0, .spacing = 0.25});
  const double z = 10.0 + 6.0 - 3.0;  // 3 m deep
  pipe.beginStroke(tool, {{20.0, 64.0, z}, 0.0});
  pipe.moveTo({{100.0, 64.0, z}, 0.0});
  pipe.endStroke();
  for (int u : {40, 60, 80}) {
    EXPECT_LT(t.height(u, 64), 10.0 - 2.0) << u;  // the furrow
    double ridgeN = 0, ridgeS = 0;
    for (int d = 5; d <= 12; ++d) {
      ridgeN = std::max(ridgeN, double(t.height(u, 64 + d)));
      ridgeS = std::max(ridgeS, double(t.height(u, 64 - d)));
    }
    EXPECT_GT(ridgeN, 10.5) << u;  // a ridge on either side
    EXPECT_GT(ridgeS, 10.5) << u;
    EXPECT_EQ(t.height(u, 64 + 20), 10.0f) << u;  // beyond the ridges: untouched
  }
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}

TEST(SandDisplacement, BadInputIsRefusedNamingTheParameterAndLeavesTheTerrainUnchanged) {
  auto chart = sphereChart(7, 20e3);
  auto t = terrain::Terrain(chart, testkit::bumpyHeights(*chart, 5, 100.0));
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  const auto codes = t.bounds().codes();
  edit::EditPipeline pipe(t);
  const double cell = sand::largestSpacing(*chart);
  auto expectRefused = [&](sand::DisplacementSettings s, const std::string& word) {
    sand::DisplacementTool tool(chart, s);
    try {
      pipe.apply(tool, {pointAbove(*chart, 10, 10, 0), 0.0});
      ADD_FAILURE() << word << ": accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
    EXPECT_TRUE(sameFloats(t.heights(), before)) << word;
    EXPECT_TRUE(t.bounds().codes() == codes) << word;
  };
  expectRefused({.radius = 0.5 * cell}, "radius");
  expectRefused({.radius = 20e3 * 1.01}, "radius");
  expectRefused({.radius = -1.0}, "radius");
  expectRefused({.radius = std::nan("")}, "radius");
  expectRefused({.radius = 3000.0, .rampartWidth = 0.0}, "rampart");
  sand::Material bad = sand::Material::sand();
  bad.talusDeg = 90.0;
  expectRefused({.radius = 3000.0, .material = bad}, "talus");
  bad = sand::Material::sand();
  bad.talusDeg = 0.0;
  expectRefused({.radius = 3000.0, .material = bad}, "talus");
  bad = sand::Material::sand();
  bad.diffusion = -0.5;
  expectRefused({.radius = 3000.0, .material = bad}, "diffusion D");
  bad = sand::Material::sand();
  bad.frictionInverse = -1e-4;
  expectRefused({.radius = 3000.0, .material = bad}, "zeta");
  // A flat grid: larger than the grid is refused too.
  auto flat = flatChart(5);
  EXPECT_THROW(sand::DisplacementSettings({.radius = 100.0}).validate(flat.get()),
               core::InputError);
  EXPECT_THROW(sand::DisplacementSettings({.radius = 0.9}).validate(flat.get()), core::InputError);
  EXPECT_NO_THROW(sand::DisplacementSettings({.radius = 1.0}).validate(flat.get()));
  // Settler settings.
  EXPECT_THROW(sand::Settler(t, sand::Material::sand(), {.cellBudget = 0}), core::InputError);
  EXPECT_THROW(sand::Settler(t, bad), core::InputError);
  EXPECT_THROW(sand::settleMethodFromString("lava"), core::InputError);
  EXPECT_THROW(sand::Material::preset("lava"), core::InputError);
}

TEST(SandSettler, CraterSettlesOverSeveralFramesUpdatingBoundsOnlyWhereItChanged) {
  // A 20 km planet (1 km cells), craters at the seam and on the north pole, settled under a
  // budget of 100,000 cell-steps per frame.
  auto chart = sphereChart(7, 20e3);
  auto t = terrain::Terrain(chart, testkit::bumpyHeights(*chart, 7, 100.0));
  edit::EditPipeline pipe(t);
  sand::Settler settler(t, sand::Material::sand(), {.cellBudget = 100000});
  sand::DisplacementTool tool(chart, {.radius = 4000.0}, &settler);
  const sand::SandGrid grid(chart);
  const double v0 = grid.volume(t.heights());
  pipe.apply(tool, {pointAbove(*chart, 20.0, 180.0, 4000.0 - 2000.0), 0.0});
  pipe.apply(tool, {pointAbove(*chart, 90.0, 0.0, 4000.0 - 2000.0), 0.0});
  std::size_t over = 0;
  std::size_t largestDirty = 0;
  int frames = 0;
  while (frames < 3000) {
    const sand::FrameReport r = settler.frame();
    ++frames;
    if (r.steps > 1 && r.cellSteps > 100000) over = std::max(over, r.cellSteps - 100000);
    if (!r.dirty.empty()) {
      largestDirty = std::max(largestDirty, std::size_t(r.dirty.vEnd - r.dirty.vBegin + 1));
    }
    if (r.atRest) break;
  }
  EXPECT_TRUE(settler.atRest());
  EXPECT_GT(frames, 3);
  EXPECT_EQ(over, 0u);  // a frame of several steps stays within the budget
  EXPECT_LT(largestDirty, std::size_t(t.grid().m()));  // never the whole planet
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  terrain::ErrorBounds full;
  full.build(t.chart(), t.heights(), t.bounds().rule());
  EXPECT_EQ(full.codes(), t.bounds().codes());
  EXPECT_LE(sandtest::worstTalusExcess(settler.field(), settler.material()),
            settler.material().talusTolerance * (1 + 1e-9));
  // Volume: displacement and settling keep it up to float rounding of the heights.
  EXPECT_LE(std::abs(grid.volume(t.heights()) - v0) / grid.absVolume(t.heights()), 1e-6);
  // At rest a frame does nothing.
  const auto revision = t.revision();
  const sand::FrameReport idle = settler.frame();
  EXPECT_EQ(idle.cellSteps, 0u);
  EXPECT_EQ(t.revision(), revision);
}

TEST(SandSettler, DiffusionSettlingKeepsVolumeAndBoundsOnFlatAndSphere) {
  for (bool sphere : {false, true}) {
    for (sand::SettleMethod method :
         {sand::SettleMethod::kDiffusionExplicit, sand::SettleMethod::kDiffusionSemiImplicit}) {
      std::shared_ptr<const core::Chart> chart =
          sphere ? std::shared_ptr<const core::Chart>(sphereChart(7, 20e3)) : flatChart(7);
      terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 20.0f));
      edit::EditPipeline pipe(t);
      sand::Settler settler(t, sand::Material::mud(),
                            {.method = method, .cellBudget = 50000, .diffusionDt = 1.0});
      const double r = sphere ? 4000.0 : 8.0, depth = sphere ? 3000.0 : 6.0;
      sand::DisplacementTool tool(chart, {.radius = r, .material = sand::Material::sand()},
                                  &settler);
      const sand::SandGrid grid(chart);
      const double v0 = grid.volume(t.heights());
      if (sphere) {
        // The explicit step near a pole is held to a tiny dt by the ring cells (docs/SAND.md):
        // explicit at 30 degrees, semi-implicit on the pole.
        const double lat = method == sand::SettleMethod::kDiffusionExplicit ? 30.0 : 88.0;
        pipe.apply(tool, {pointAbove(*chart, lat, 180.0, 20.0 + r - depth), 0.0});
      } else {
        pipe.apply(tool, {{50.0, 70.0, 20.0 + r - depth}, 0.0});
      }
      const int frames = settleFrames(settler, 3000, 50000);
      const std::string what = (sphere ? "sphere " : "flat ") + toString(method);
      EXPECT_TRUE(settler.atRest()) << what << " " << frames;
      EXPECT_GT(frames, 1) << what;
      EXPECT_EQ(settler.material().name, "sand");  // the tool's material
      EXPECT_TRUE(edittest::boundsEqualFullRebuild(t)) << what;
      EXPECT_TRUE(edittest::consistentHeights(t)) << what;
      EXPECT_LE(std::abs(grid.volume(t.heights()) - v0) / grid.absVolume(t.heights()), 1e-6)
          << what;
    }
  }
}

TEST(SandSettler, PicksUpEditsMadeBehindItsBack) {
  auto chart = flatChart(6);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 0.0f));
  edit::EditPipeline pipe(t);
  sand::Settler settler(t);
  sand::DisplacementTool tool(chart, {.radius = 5.0}, &settler);
  pipe.apply(tool, {{20.0, 20.0, 5.0 - 4.0}, 0.0});
  settleFrames(settler, 1000, 1 << 20);
  ASSERT_TRUE(settler.atRest());
  // A brush spike inside the settled area, not reported: the settler re-reads what it holds.
  edit::BrushSettings b;
  b.radius = 3.0;
  b.strength = 30.0;
  edit::GaussianBrush brush(b);
  pipe.apply(brush, {{20.0, 20.0, 0.0}, 0.0});
  const sand::FrameReport r = settler.frame();
  EXPECT_GT(r.cellSteps, 0u);
  settleFrames(settler, 1000, 1 << 20);
  EXPECT_LE(sandtest::worstTalusExcess(settler.field(), settler.material()),
            settler.material().talusTolerance * (1 + 1e-9));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  // Undo of the brush stroke is picked up the same way.
  pipe.undo();
  settleFrames(settler, 1000, 1 << 20);
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}
