#include <gtest/gtest.h>

#include <random>

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
