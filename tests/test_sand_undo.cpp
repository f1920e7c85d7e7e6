// Undo of sand strokes with the settling that followed them (Settler::attachUndo): random
// displacement strokes, settling frames during and after each, then every stroke undone in turn,
// with settling running between the undos. Each undo must bring the planet back bit for bit to
// its state when that stroke began: the heights and the error bounds.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/octahedral_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/settler.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

struct Case {
  std::string name;
  std::shared_ptr<const core::Chart> chart;
  double radius, depth;  // the tool's sphere and how deep it presses
};

std::vector<Case> cases() {
  return {
      {"flat", sandtest::flatChart(7), 8.0, 5.0},
      {"lat-long", sandtest::sphereChart(7, 20e3), 4000.0, 2000.0},
      {"octahedral",
       std::make_shared<core::OctahedralChart>(core::GridSize(7), 20e3,
                                               core::OctahedralChart::Mapping::kEqualArea),
       4000.0, 2000.0},
  };
}

struct State {
  std::vector<float> heights;
  std::vector<std::uint16_t> error;
};

State capture(const terrain::Terrain& t) {
  return {{t.heights().begin(), t.heights().end()}, t.bounds().errorCodes()};
}

bool same(const terrain::Terrain& t, const State& s) {
  return edittest::sameBits(t.heights(), s.heights) && t.bounds().errorCodes() == s.error;
}

// A point `depth` below the tool's top: on the sphere at a random direction (poles, folds and
// the seam included), on the flat grid anywhere inside it.
Eigen::Vector3d toolCentre(const Case& c, std::mt19937& rng) {
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  if (c.chart->sphereRadius() > 0.0) {
    Eigen::Vector3d d(uni(rng), uni(rng), uni(rng));
    return d.normalized() * (c.chart->sphereRadius() + c.radius - c.depth);
  }
  const double m = c.chart->grid().m();
  return {m * (0.5 + 0.4 * uni(rng)), m * (0.5 + 0.4 * uni(rng)), 20.0 + c.radius - c.depth};
}

// The scenario: random strokes with settling during and after each, then every stroke undone in
// turn with settling between the undos. Returns a failure naming the first state that did not
// come back bit for bit (`attach`: the settler reports to the pipeline's journal).
::testing::AssertionResult strokesUndoBitForBit(const Case& c, bool attach) {
  const bool sphere = c.chart->sphereRadius() > 0.0;
  terrain::Terrain t(c.chart, sphere ? testkit::bumpyHeights(*c.chart, 9, 100.0)
                                     : std::vector<float>(c.chart->grid().count(), 20.0f));
  edit::EditPipeline pipe(t);
  sand::Settler settler(t, sand::Material::sand(), {.cellBudget = 30000});
  if (attach) settler.attachUndo(&pipe);
  sand::DisplacementTool tool(c.chart, {.radius = c.radius}, &settler);
  // The start at rest (with nothing to undo yet, this settling is not journaled).
  settler.settleAll();
  for (int f = 0; f < 2000 && !settler.atRest(); ++f) settler.frame();
  if (!settler.atRest() || pipe.journal().bytes() != 0)
    return ::testing::AssertionFailure() << "the start did not come to rest unjournaled";
  std::mt19937 rng(17);
  std::vector<State> begins;
  int settledDuringStrokes = 0;
  for (int stroke = 0; stroke < 6; ++stroke) {
    begins.push_back(capture(t));
    Eigen::Vector3d p = toolCentre(c, rng);
    pipe.beginStroke(tool, {p, 0.0});
    for (int k = 0; k < 3; ++k) {
      settledDuringStrokes += settler.frame().dirty.empty() ? 0 : 1;
      const Eigen::Vector3d q = toolCentre(c, rng);
      p = p + 0.05 * (q - p);  // a short drag
      if (sphere) p = p.normalized() * (c.chart->sphereRadius() + c.radius - c.depth);
      pipe.moveTo({p, 0.0});
    }
    pipe.endStroke();
    for (int f = int(rng() % 4); f > 0; --f) settler.frame();
  }
  if (settledDuringStrokes == 0 || settler.atRest())
    return ::testing::AssertionFailure() << "the scenario must settle during strokes and after";
  // Undo straight after a frame, then redo: the state the undo found.
  const State last = capture(t);
  pipe.undo();
  if (!same(t, begins.back())) return ::testing::AssertionFailure() << "undo of the last stroke";
  pipe.redo();
  if (!same(t, last)) return ::testing::AssertionFailure() << "redo";
  // Every stroke undone in turn, settling between the undos (what it moves after an undo joins
  // the stroke below, so that stroke's undo takes it back too).
  for (int i = int(begins.size()) - 1; i >= 0; --i) {
    pipe.undo();
    if (!same(t, begins[std::size_t(i)]))
      return ::testing::AssertionFailure() << "after undoing stroke " << i;
    for (int f = 0; f < 3; ++f) settler.frame();
    if (i == 3) {  // a redo over what settled since the undo, more settling, the undo again
      pipe.redo();
      for (int f = 0; f < 3; ++f) settler.frame();
      pipe.undo();
      for (int f = 0; f < 3; ++f) settler.frame();
    }
  }
  // Back at the start, which was at rest: the frames after the last undo moved nothing.
  if (!same(t, begins.front()) || !settler.atRest())
    return ::testing::AssertionFailure() << "settling moved the restored start";
  if (!edittest::consistentHeights(t) || !edittest::boundsEqualFullRebuild(t))
    return ::testing::AssertionFailure() << "twins or bounds";
  return ::testing::AssertionSuccess();
}

}  // namespace

TEST(SandUndo, UndoingSandStrokesTakesTheirSettlingBackBitForBit) {
  for (const Case& c : cases()) {
    EXPECT_TRUE(strokesUndoBitForBit(c, true)) << c.name;
    // Without the settler reporting to the journal, undo restores the stamps' footprints only
    // and the settled sand outside them stays: the scenario must see that.
    EXPECT_FALSE(strokesUndoBitForBit(c, false)) << c.name;
  }
}
