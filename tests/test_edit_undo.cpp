#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include "core/input_error.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using edit::BrushMode;
using edit::BrushSettings;
using edit::GaussianBrush;

namespace {

struct State {
  std::vector<float> heights;
  std::vector<std::uint16_t> error, radius;
};
State capture(const terrain::Terrain& t) {
  return {
      {t.heights().begin(), t.heights().end()}, t.bounds().errorCodes(), t.bounds().radiusCodes()};
}
::testing::AssertionResult same(const terrain::Terrain& t, const State& s) {
  if (!edittest::sameBits(t.heights(), s.heights))
    return ::testing::AssertionFailure() << "heights differ";
  if (t.bounds().errorCodes() != s.error)
    return ::testing::AssertionFailure() << "error codes differ";
  if (t.bounds().radiusCodes() != s.radius)
    return ::testing::AssertionFailure() << "radius codes differ";
  return ::testing::AssertionSuccess();
}

}  // namespace

TEST(EditUndo, UndoAndRedoRestoreHeightsAndBoundsBitForBit) {
  auto t = testkit::bumpyTerrain(7, 12, 5000.0);
  edit::EditPipeline pipe(t);
  std::mt19937 rng(12);
  GaussianBrush brush;
  std::vector<State> states{capture(t)};
  for (int i = 0; i < 8; ++i) {
    edittest::randomStroke(pipe, rng, brush);
    states.push_back(capture(t));
  }
  ASSERT_EQ(pipe.journal().undoCount(), 8u);
  for (int i = 7; i >= 0; --i) {
    pipe.undo();
    ASSERT_TRUE(same(t, states[std::size_t(i)])) << "after undoing back to state " << i;
  }
  EXPECT_THROW(pipe.undo(), core::InputError);
  for (int i = 1; i <= 8; ++i) {
    pipe.redo();
    ASSERT_TRUE(same(t, states[std::size_t(i)])) << "after redoing to state " << i;
  }
  EXPECT_THROW(pipe.redo(), core::InputError);
  // Undo some, then a new stroke: the redo branch is gone.
  pipe.undo();
  pipe.undo();
  ASSERT_TRUE(same(t, states[6]));
  EXPECT_EQ(pipe.journal().redoCount(), 2u);
  edittest::randomStroke(pipe, rng, brush);
  EXPECT_EQ(pipe.journal().redoCount(), 0u);
  pipe.undo();
  EXPECT_TRUE(same(t, states[6]));
  EXPECT_TRUE(edittest::consistentHeights(t));
}

TEST(EditUndo, MemoryIsProportionalToWhatChanged) {
  auto t = testkit::bumpyTerrain(8, 3, 5000.0);
  edit::EditPipeline pipe(t);
  BrushSettings s;
  s.radius = 300e3;
  s.strength = 800;
  GaussianBrush brush(s);
  const Eigen::Vector3d p = t.chart().position(100, 60, 0.0);
  const auto rep = pipe.apply(brush, {p, 0});
  const std::size_t changed = pipe.journal().lastStrokeChanges();
  EXPECT_GT(changed, 0u);
  EXPECT_LE(changed, rep.modifiedVertices);
  EXPECT_LE(pipe.journal().bytes(), changed * sizeof(edit::HeightChange) + 512);
  EXPECT_LT(pipe.journal().bytes(), t.grid().count() / 50) << "far below a copy of the planet";
  // A long stroke scrubbing back and forth over the same place: each vertex is stored once.
  pipe.beginStroke(brush, {p, 0});
  const Eigen::Vector3d q = t.chart().position(104, 60, 0.0);
  for (int k = 0; k < 40; ++k) pipe.moveTo({(k & 1) ? p : q, 0});
  pipe.endStroke();
  const std::size_t union_ = pipe.journal().lastStrokeChanges();
  EXPECT_LE(union_, 2 * rep.modifiedVertices);
  EXPECT_LE(pipe.journal().bytes(), (changed + union_) * sizeof(edit::HeightChange) + 1024);
}

TEST(EditUndo, OldStrokesAreForgottenBeyondTheCap) {
  auto t = testkit::bumpyTerrain(6, 3, 5000.0);
  edit::EditPipeline pipe(t);
  pipe.journal().setMaxBytes(1);  // keeps only the newest stroke
  std::mt19937 rng(2);
  GaussianBrush brush;
  for (int i = 0; i < 4; ++i) edittest::randomStroke(pipe, rng, brush);
  EXPECT_EQ(pipe.journal().undoCount(), 1u);
  const State before = capture(t);
  pipe.undo();
  pipe.redo();
  EXPECT_TRUE(same(t, before));
}

TEST(EditUndo, DisabledJournalRecordsNothing) {
  auto t = testkit::bumpyTerrain(6, 3, 5000.0);
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  const GaussianBrush brush;
  const auto rep = pipe.apply(brush, {t.chart().position(5, 5, 0.0), 0});
  EXPECT_GT(rep.modifiedVertices, 0u);  // the edit happened
  EXPECT_EQ(pipe.journal().undoCount(), 0u);
  EXPECT_EQ(pipe.journal().bytes(), 0u);
  EXPECT_THROW(pipe.undo(), core::InputError);
}

namespace {

// What settling does to the heights, as the settler does it: interior vertices (no seam twin, no
// pole row) set to new values, committed, and reported to the pipeline's journal.
void changeOutside(edit::EditPipeline& pipe, const std::vector<std::pair<int, int>>& at,
                   float delta) {
  terrain::Terrain& t = pipe.terrain();
  const core::GridSize g = t.grid();
  auto h = t.mutableHeights();
  std::vector<edit::HeightChange> changes;
  terrain::VertexBox box = terrain::VertexBox::none();
  for (auto [u, v] : at) {
    const std::size_t k = g.index(u, v);
    changes.push_back({std::uint32_t(k), h[k], h[k] + delta});
    h[k] += delta;
    box = box.unite(terrain::VertexBox{u, u, v, v}, g, t.chart().wrapsU());
  }
  t.commitEdit(box);
  pipe.recordOutside(changes, box);
}

struct HeardChanges final : edit::JournalListener {
  std::vector<std::vector<std::uint32_t>> indices;
  void onCommitted(edit::JournalEvent, std::span<const edit::HeightChange> c) noexcept override {
    std::vector<std::uint32_t> i;
    for (const auto& x : c) i.push_back(x.index);
    indices.push_back(std::move(i));
  }
};

}  // namespace

TEST(EditUndo, ChangesFromOutsideJoinTheOpenOrLatestStrokeAndUndoTakesThemBack) {
  auto t = testkit::bumpyTerrain(6, 4, 5000.0);
  edit::EditPipeline pipe(t);
  HeardChanges heard;
  pipe.journal().setListener(&heard);
  BrushSettings s;
  s.radius = 400e3;
  s.strength = 900;
  GaussianBrush brush(s);
  const State start = capture(t);
  const Eigen::Vector3d p = t.chart().position(20, 30, 0.0);
  // Far from the stroke, inside it, and one vertex twice (its first "before" must win).
  const std::vector<std::pair<int, int>> far{{50, 10}, {51, 10}, {40, 50}};
  pipe.beginStroke(brush, {p, 0});
  changeOutside(pipe, far, 3.5f);
  changeOutside(pipe, {{20, 30}, {50, 10}}, -1.25f);
  pipe.moveTo({t.chart().position(24, 30, 0.0), 0});
  pipe.endStroke();
  // After the stroke ended, before the next: joins it.
  changeOutside(pipe, {{60, 60}, {40, 50}}, 7.0f);
  const State end = capture(t);
  EXPECT_EQ(pipe.journal().undoCount(), 1u);
  pipe.undo();
  EXPECT_TRUE(same(t, start)) << "undo takes the stroke and what followed it back";
  pipe.redo();
  EXPECT_TRUE(same(t, end));
  // The stroke's record (the listener) names the vertices settling moved during it.
  ASSERT_EQ(heard.indices.size(), 3u);  // stroke, undo, redo
  for (auto [u, v] : far) {
    EXPECT_TRUE(std::binary_search(heard.indices[0].begin(), heard.indices[0].end(),
                                   std::uint32_t(t.grid().index(u, v))))
        << u << "," << v;
  }
  // Changed from outside after undoing the only stroke: nothing to join, not recorded; the
  // stroke stays redoable and its redo writes its "after" heights.
  pipe.undo();
  const std::size_t bytes = pipe.journal().bytes();
  changeOutside(pipe, {{5, 5}}, 1.0f);
  EXPECT_EQ(pipe.journal().redoCount(), 1u);
  EXPECT_EQ(pipe.journal().bytes(), bytes);
  EXPECT_THROW(pipe.undo(), core::InputError);
  pipe.redo();
  for (auto [u, v] : far) {
    const std::size_t k = t.grid().index(u, v);
    EXPECT_EQ(t.heights()[k], end.heights[k]) << u << "," << v;
  }
}

TEST(EditUndo, AVertexMovedFromOutsideAndBackWithinAStrokeStaysInIt) {
  // Moved by settling, then back to its first height within the stroke (by settling or a stamp):
  // a no-op for undo, but kept, so that the stroke's record writes the height it ends with.
  auto t = testkit::bumpyTerrain(6, 5, 5000.0);
  edit::EditPipeline pipe(t);
  HeardChanges heard;
  pipe.journal().setListener(&heard);
  GaussianBrush brush;
  pipe.beginStroke(brush, {t.chart().position(20, 20, 0.0), 0});
  changeOutside(pipe, {{50, 50}}, 2.0f);
  changeOutside(pipe, {{50, 50}}, -2.0f);
  const float back = t.heights()[t.grid().index(50, 50)];
  pipe.endStroke();
  ASSERT_EQ(heard.indices.size(), 1u);
  const std::uint32_t k = std::uint32_t(t.grid().index(50, 50));
  EXPECT_TRUE(std::binary_search(heard.indices[0].begin(), heard.indices[0].end(), k));
  pipe.undo();
  EXPECT_EQ(t.heights()[k], back);
  // No index keeps the journal's internal mark.
  for (std::uint32_t i : heard.indices[0]) EXPECT_LT(i, std::uint32_t(t.grid().count()));
}

TEST(EditUndo, OutsideChangesAreIgnoredWithUndoOff) {
  auto t = testkit::bumpyTerrain(6, 3, 5000.0);
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  changeOutside(pipe, {{10, 10}}, 1.0f);
  EXPECT_EQ(pipe.journal().bytes(), 0u);
}

TEST(EditUndo, ALongSettleAfterAStrokeIsMergedAndKeepsOneEntryAVertex) {
  // Settling that changes more than the stroke did, frame after frame: gathered, merged into the
  // stroke (each vertex once), and taken back by its undo.
  auto t = testkit::bumpyTerrain(8, 6, 5000.0);
  edit::EditPipeline pipe(t);
  GaussianBrush brush;
  const State start = capture(t);
  pipe.apply(brush, {t.chart().position(100, 100, 0.0), 0});
  const int m = t.grid().m();
  std::vector<std::pair<int, int>> interior;
  for (int v = 1; v < m; ++v) {
    for (int u = 1; u < m; ++u) interior.push_back({u, v});
  }
  for (int frame = 0; frame < 5; ++frame) changeOutside(pipe, interior, frame % 2 ? -0.5f : 1.0f);
  const State end = capture(t);
  // The grid's interior recorded five times, kept once (plus what has not been merged yet).
  EXPECT_LE(pipe.journal().bytes(), 2 * interior.size() * sizeof(edit::HeightChange) + 4096);
  pipe.undo();
  EXPECT_TRUE(same(t, start));
  pipe.redo();
  EXPECT_TRUE(same(t, end));
  EXPECT_GE(pipe.journal().lastStrokeChanges(), interior.size());
}
