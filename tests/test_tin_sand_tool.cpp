// The sand TIN as an edit tool: through the edit pipeline on a flat grid and on a planet (the
// equator, the seam, next to a pole and on it), the grid's volume kept, seam twins and pole rows
// one point, the bounds equal to a full rebuild, undo bit for bit, the same result twice.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/input_error.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/sand_grid.hpp"
#include "sand/tin_sand_tool.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

sand::TinSandToolSettings settings(double radius, int segments = 24, double region = 3.0,
                                   int erosionSteps = 8) {
  sand::TinSandToolSettings s;
  s.radius = radius;
  s.segments = segments;
  s.regionRadius = region;
  s.erosionSteps = erosionSteps;
  return s;
}

using edittest::pointAbove;

TEST(TinSandTool, PressesAFlatBoxKeepingItsVolumeAndUndoesBitForBit) {
  auto chart = sandtest::flatChart(7);  // 129^2, 1 m cells
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 20.0f));
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  sand::TinSandTool tool(chart, settings(8.0));
  const sand::SandGrid grid(chart);
  const double v0 = grid.volume(t.heights());
  // The sphere's lowest point 4 m under the sand.
  pipe.apply(tool, {{64.0, 64.0, 20.0 - 4.0 + 8.0}, 0.0});
  const auto& s = tool.lastStats();
  EXPECT_GT(s.displacedVolume, 0.5 * M_PI * 8 * 8 * 4) << "a disc about 4 m deep";
  EXPECT_GT(s.changed, 200u);
  EXPECT_LT(t.height(64, 64), 20.0 - 1.0) << "the imprint survives 8 erosion iterations";
  EXPECT_LE(std::abs(grid.volume(t.heights()) - v0) / grid.absVolume(t.heights()), 1e-12);
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  for (const float h : t.heights()) ASSERT_TRUE(std::isfinite(h));
  pipe.undo();
  EXPECT_TRUE(std::equal(before.begin(), before.end(), t.heights().begin()));
}

TEST(TinSandTool, WorksOnThePlanetAtTheEquatorTheSeamAndThePoles) {
  auto chart = sandtest::sphereChart(8, 20e3);  // a 20 km planet, ~490 m cells
  terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 3, 100.0));
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  sand::TinSandTool tool(chart, settings(1200.0));
  const sand::SandGrid grid(chart);
  for (auto [lat, lon] : {std::pair{0.0, 10.0}, {5.0, 180.0}, {-86.0, 40.0}, {90.0, 0.0}}) {
    const double vBefore = grid.volume(t.heights());
    pipe.apply(tool, {pointAbove(*chart, lat, lon, 1200.0 - 300.0), 0.0});
    const auto& s = tool.lastStats();
    EXPECT_GT(s.displacedVolume, 1e8) << lat << " " << lon;
    EXPECT_GT(s.gridVertices, 30u) << lat << " " << lon;
    if (std::abs(lat) > 80) {
      EXPECT_LT(s.tinStartVertices, s.gridVertices) << "the pole's crowded rows are thinned";
    } else {
      EXPECT_EQ(s.tinStartVertices, s.gridVertices) << lat << " " << lon;
    }
    EXPECT_LE(std::abs(grid.volume(t.heights()) - vBefore) / grid.absVolume(t.heights()), 1e-9)
        << lat << " " << lon;
    EXPECT_TRUE(edittest::consistentHeights(t)) << lat << " " << lon;
  }
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}

TEST(TinSandTool, TheSameStrokeGivesTheSameHeights) {
  const auto run = [] {
    auto chart = sandtest::sphereChart(8, 20e3);
    terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 5, 80.0));
    edit::EditPipeline pipe(t);
    sand::TinSandTool tool(chart, settings(1200.0));
    for (int k = 0; k < 6; ++k)
      pipe.apply(tool, {pointAbove(*chart, 30.0, 176.0 + 1.5 * k, 1200.0 - 300.0), 0.0});
    return std::vector<float>(t.heights().begin(), t.heights().end());
  };
  const auto a = run(), b = run();
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
}

TEST(TinSandTool, RefusesSettingsItCannotHonour) {
  auto chart = sandtest::flatChart(7);
  auto planet = sandtest::sphereChart(7, 20e3);
  const auto refuses = [&](sand::TinSandToolSettings s, const char* says,
                           const core::Chart* on = nullptr) {
    try {
      s.validate(on ? on : chart.get());
      ADD_FAILURE() << "accepted; expected: " << says;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refuses(settings(1.0), "under two grid cells");
  refuses(settings(8.0, 2), "segments");
  refuses(settings(8.0, 24, 2.0), "region radius");
  refuses(settings(8.0, 24, 3.0, -1), "erosion steps");
  sand::TinSandToolSettings bad = settings(8.0);
  bad.sand.material.talusDeg = 0;
  EXPECT_THROW(bad.validate(chart.get()), core::InputError);
  refuses(settings(3000.0, 24, 4.0), "too curved", planet.get());
}

}  // namespace
