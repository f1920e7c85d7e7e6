#include <gtest/gtest.h>

#include <random>

#include "app/build_paths.hpp"
#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "edit/brush.hpp"
#include "edit/control_vertex.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/stroke_script.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using edit::ScriptCommand;

namespace {
std::string scriptErrorOf(const std::string& text, edit::EditPipeline& pipe) {
  try {
    edit::runStrokeScript(edit::parseStrokeScript(text, "bad.txt"), pipe);
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(EditScript, DemoFileRunsOnAPlanet) {
  const auto script = edit::loadStrokeScript(ps::app::sourceDir() / "data/demo-strokes.txt");
  ASSERT_GT(script.commands.size(), 10u);
  auto t = testkit::bumpyTerrain(7, 6, 5000.0);
  const std::vector<float> start(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  const auto rep = edit::runStrokeScript(script, pipe);
  EXPECT_GE(rep.strokes, 6);
  EXPECT_EQ(rep.undos, 1);
  EXPECT_GT(rep.edits.stamps, 20);
  EXPECT_FALSE(edittest::sameBits(t.heights(), start));
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  // The crater straddles the seam: both twins went down together.
  const auto c = edit::nearestVertex(
      t.chart(), edit::scriptPosition({false, {-20, 179.5, 0}}, t.chart().sphereRadius()));
  EXPECT_LT(t.height(c.u, c.v), start[t.grid().index(c.u, c.v)]);
}

// A LAT LON point is a direction on the chart's sphere: on a torus, a cylinder or a flat grid
// (sphereRadius() 0, no sphere) it is refused by line before anything is stamped, where taking
// the 0 as a size would have put the stamp at the origin; an xyz point stamps there as anywhere.
TEST(EditScript, LatLonPointsAreRefusedOnChartsThatAreNoSphere) {
  const std::vector<std::shared_ptr<const core::Chart>> charts{
      std::make_shared<core::TorusChart>(core::GridSize(6), 4.5e6, 1.8e6),
      std::make_shared<core::CylinderChart>(core::GridSize(6), 3e6, 6e6),
      std::make_shared<core::FlatChart>(core::GridSize(6), 1e4, 1e4)};
  for (const auto& chart : charts) {
    SCOPED_TRACE(chart->name());
    EXPECT_EQ(chart->sphereRadius(), 0.0);
    terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 5, 200.0));
    const std::vector<float> start(t.heights().begin(), t.heights().end());
    edit::EditPipeline pipe(t);
    const Eigen::Vector3d p = chart->position(20, 30, 0.0);
    const int m = chart->grid().m();
    const double r_km =
        0.1 * (chart->position(m / 2, m / 2, 0.0) - chart->position(0, 0, 0.0)).norm() / 1e3;
    const std::string brush = "brush r_km=" + std::to_string(r_km) + " sigma=0.3\n";
    const std::string xyz = "stamp xyz=" + std::to_string(p.x()) + "," + std::to_string(p.y()) +
                            "," + std::to_string(p.z()) + "\n";
    const std::string err = scriptErrorOf(brush + xyz + "stamp 10 20\n", pipe);
    EXPECT_NE(err.find("bad.txt:3: a LAT LON point needs a sphere"), std::string::npos) << err;
    EXPECT_TRUE(edittest::sameBits(t.heights(), start)) << "a refused script changed heights";
    EXPECT_EQ(scriptErrorOf(brush + xyz, pipe), "");
    EXPECT_FALSE(edittest::sameBits(t.heights(), start)) << "the xyz stamp changed nothing";
  }
}

TEST(EditScript, ErrorsNameTheFileLineAndValueAndTouchNothing) {
  auto t = testkit::bumpyTerrain(6, 6, 5000.0);
  edit::EditPipeline pipe(t);
  const std::vector<float> start(t.heights().begin(), t.heights().end());
  const auto revision = t.revision();
  const std::string ok = "# fine so far\nbrush r_km=300 sigma=0.17\nstamp 10 20\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {ok + "brush r_km=-3\n", "bad.txt:4: radius of deformation r_d = -3000"},
      {ok + "brush r_km=0\n", "bad.txt:4: radius of deformation r_d = 0"},
      {ok + "brush r_km=nan\n", "bad.txt:4: radius of deformation r_d = nan"},
      {ok + "brush sigma=0\n", "bad.txt:4: sigma = 0"},
      {ok + "brush sigma=-0.5\n", "bad.txt:4: sigma = -0.5"},
      {ok + "brush sigma=abc\n", "bad.txt:4: sigma 'abc' is not a number"},
      {ok + "brush mode=flatten\n", "bad.txt:4: brush mode 'flatten'"},
      {ok + "brush colour=red\n", "bad.txt:4: brush: unknown key 'colour'"},
      {ok + "stamp 95 0\n", "bad.txt:4: latitude 95 degrees"},
      {ok + "stamp 10\n", "bad.txt:4: stamp needs a point"},
      {ok + "stamp 10 x20\n", "bad.txt:4: stamp longitude 'x20' is not a number"},
      {ok + "stamp xyz=0,0,0\n", "bad.txt:4: tool position (0, 0, 0) m is at the planet's centre"},
      {ok + "stamp xyz=1,inf,0\n", "bad.txt:4: tool position (1, inf, 0) m is not finite"},
      {ok + "stamp 10 20 dt=-1\n", "bad.txt:4: dt = -1"},
      {ok + "stamp 10 20 speed=3\n", "bad.txt:4: stamp: unexpected 'speed=3'"},
      {ok + "to 10 20\n", "bad.txt:4: 'to' outside a stroke"},
      {ok + "end\n", "bad.txt:4: 'end' without a stroke"},
      {ok + "stroke 1 2\nstroke 3 4\nend\n", "bad.txt:5: stroke inside a stroke (begun on line 4)"},
      {ok + "stroke 1 2\nto 3 4\n", "bad.txt:4: this stroke is never ended"},
      {ok + "stroke 1 2\nbrush mu=2\nend\n", "bad.txt:5: the brush cannot change inside a stroke"},
      {ok + "undo 2\n", "bad.txt:4: undo 2: only 1 step(s) can be undone"},
      {ok + "redo\n", "bad.txt:4: redo 1: only 0 step(s) can be redone"},
      {ok + "undo zero\n", "bad.txt:4: undo count 'zero'"},
      {ok + "sculpt 1 2\n", "bad.txt:4: unknown command 'sculpt'"},
  };
  for (const auto& [text, expect] : cases) {
    const std::string e = scriptErrorOf(text, pipe);
    EXPECT_NE(e.find(expect), std::string::npos) << "got: '" << e << "'\nexpected: " << expect;
    ASSERT_TRUE(edittest::sameBits(t.heights(), start)) << "planet changed by: " << text;
    ASSERT_EQ(t.revision(), revision);
    ASSERT_EQ(pipe.journal().undoCount(), 0u);
  }
  EXPECT_THROW(edit::loadStrokeScript("/nonexistent/strokes.txt"), core::InputError);
  pipe.setUndoEnabled(false);
  EXPECT_NE(scriptErrorOf(ok + "undo\n", pipe).find("bad.txt:4: undo needs the undo journal"),
            std::string::npos);
}

TEST(EditScript, TextRoundTripsExactly) {
  const std::string text =
      "brush r_km=250 sigma=0.75 mu=1.25 mode=set target_m=-120.5 rate_mps=3.25 spacing=0.5\n"
      "stroke 10.5 -170 dt=0.25\n"
      "to xyz=1.5e6,-2.25e6,3.125e6 dt=0.5\n"
      "end   # trailing comment\n"
      "\n"
      "stamp -89.999 359\n"
      "undo 1\n"
      "redo\n";
  const auto a = edit::parseStrokeScript(text, "a.txt");
  const auto b = edit::parseStrokeScript(a.toText(), "b.txt");
  ASSERT_EQ(a.commands.size(), 7u);
  ASSERT_EQ(b.commands.size(), a.commands.size());
  for (std::size_t i = 0; i < a.commands.size(); ++i) {
    const ScriptCommand &x = a.commands[i], &y = b.commands[i];
    EXPECT_EQ(x.kind, y.kind) << i;
    EXPECT_TRUE(x.brush == y.brush) << i;
    EXPECT_EQ(x.point.xyz, y.point.xyz) << i;
    EXPECT_EQ(x.point.value, y.point.value) << i;
    EXPECT_EQ(x.dt, y.dt) << i;
    EXPECT_EQ(x.count, y.count) << i;
  }
  EXPECT_EQ(a.commands[0].brush.radius, 250e3);
  EXPECT_TRUE(a.commands[0].brush.rate);
  EXPECT_EQ(a.commands[0].brush.mode, edit::BrushMode::kSet);
  EXPECT_EQ(a.commands[4].line, 6);
}

TEST(EditScript, RecordedJournalReplaysToTheSamePlanetBitForBit) {
  auto a = testkit::bumpyTerrain(7, 31, 5000.0);
  const terrain::Terrain start = a;
  edit::EditPipeline pipe(a);
  edit::StrokeRecorder recorder("session.txt");
  pipe.setObserver(&recorder);
  std::mt19937 rng(31);
  edit::GaussianBrush brush;
  const double R = a.chart().sphereRadius();
  for (int i = 0; i < 8; ++i) {
    edit::BrushSettings s;
    s.radius = 100e3 + 50e3 * double(rng() % 20);
    s.sigma = (rng() & 1) ? 0.17 : 0.75;
    s.mode = edit::BrushMode(rng() % 3);
    s.rate = (rng() % 3) == 0;
    s.strength = 10.0 + double(rng() % 2000);
    brush.setSettings(s);
    const core::GridPoint c = edittest::randomCentre(rng, a.grid().m());
    Eigen::Vector3d p = a.chart().position(c.u, c.v, 0.0) + 1e4 * Eigen::Vector3d::Random();
    if (i % 3 == 0) {
      pipe.apply(brush, {p, 0.3});
    } else {
      pipe.beginStroke(brush, {p, 0.1});
      for (int k = 0; k < 3; ++k) {
        p = (p + 0.1 * R * Eigen::Vector3d::Random()).normalized() * R * 1.01;
        pipe.moveTo({p, 0.05 * k});
      }
      pipe.endStroke();
    }
    if (i == 4) pipe.undo();
    if (i == 5) {
      pipe.undo();
      pipe.redo();
    }
  }
  // Replay the journal (through its text) on the starting planet.
  terrain::Terrain b = start;
  edit::EditPipeline replay(b);
  const auto script = edit::parseStrokeScript(recorder.script().toText(), "session.txt");
  edit::runStrokeScript(script, replay);
  EXPECT_TRUE(edittest::sameBits(a.heights(), b.heights()));
  EXPECT_EQ(a.bounds().errorCodes(), b.bounds().errorCodes());
  EXPECT_EQ(a.bounds().radiusCodes(), b.bounds().radiusCodes());
  EXPECT_EQ(pipe.journal().undoCount(), replay.journal().undoCount());
}

TEST(EditScript, RecorderRefusesToolsItCannotWriteBeforeTheyAct) {
  struct Nudge final : edit::Tool {
    std::string name() const override { return "nudge"; }
    void validate() const override {}
    double radius() const override { return 100e3; }
    terrain::VertexBox apply(const edit::ToolContext& ctx, std::span<float> h) const override {
      const auto g = ctx.field.grid();
      h[g.index(ctx.control.u, ctx.control.v)] += 1.0f;
      return terrain::VertexBox::point(ctx.control);
    }
  };
  auto t = testkit::bumpyTerrain(6, 1, 1000.0);
  const std::vector<float> start(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  edit::StrokeRecorder recorder;
  pipe.setObserver(&recorder);
  const Nudge nudge;
  EXPECT_THROW(pipe.apply(nudge, {t.chart().position(20, 20, 0.0), 0}), core::InputError);
  EXPECT_TRUE(edittest::sameBits(t.heights(), start));
  pipe.setObserver(nullptr);
  pipe.apply(nudge,
             {t.chart().position(20, 20, 0.0), 0});  // a custom tool through the same pipeline
  EXPECT_EQ(t.height(20, 20), start[t.grid().index(20, 20)] + 1.0f);
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
}
