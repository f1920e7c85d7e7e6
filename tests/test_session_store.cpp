// The live session's planet on disk: autosave, the stroke journal and recovery
// (session/session_store.hpp, io/stroke_journal.hpp). A "crash" is the files as they are while
// the session is still running: each record is one write(2), so that is what a killed process
// leaves behind.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "core/input_error.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "fresh_dir.hpp"
#include "io/planet_file.hpp"
#include "io/stroke_journal.hpp"
#include "replay/replay.hpp"
#include "session/session_store.hpp"
#include "short_scene.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
namespace fs = std::filesystem;
using session::Recovery;
using session::SessionFiles;
using session::SessionStore;

namespace {

using testkit::readAll;
using testkit::writeAll;

// Heights changed behind the undo journal's back, as sand settling does: a rectangle away from
// the seam and the poles, journaled by recordRegion.
void settleSomething(terrain::Terrain& t, SessionStore& store, std::mt19937& rng) {
  const int m = t.grid().m();
  const int u0 = 1 + int(rng() % unsigned(m - 8)), v0 = 2 + int(rng() % unsigned(m - 10));
  const terrain::VertexBox r{u0, u0 + 4, v0, v0 + 5};
  auto h = t.mutableHeights();
  for (int v = r.vBegin; v <= r.vEnd; ++v)
    for (int u = r.uBegin; u <= r.uEnd; ++u) h[t.grid().index(u, v)] += float(rng() % 50) - 25.f;
  t.commitEdit(r);
  store.recordRegion(r);
}

bool sameHeights(std::span<const float> a, std::span<const float> b) {
  return edittest::sameBits(a, b);
}

}  // namespace

TEST(SessionStore, CrashAfterRandomStrokesRecoversTheLiveHeightsBitForBit) {
  const fs::path dir = testkit::freshDir("session_crash");
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    auto t = testkit::bumpyTerrain(7, seed, 5000.0);
    edit::EditPipeline pipe(t);
    edit::GaussianBrush brush;
    std::mt19937 rng(seed);
    const SessionFiles files = SessionFiles::in(dir / std::to_string(seed));
    fs::create_directories(files.planet.parent_path());
    auto store =
        std::make_unique<SessionStore>(t, files, session::SessionStoreOptions{10, true}, 0.0);
    pipe.journal().setListener(store.get());
    double now = 0;
    int undos = 0, redos = 0, settles = 0;
    const int actions = 30 + int(rng() % 20);
    for (int i = 0; i < actions; ++i) {
      const unsigned a = rng() % 20;
      if (a < 3 && pipe.journal().undoCount() > 0) {
        pipe.undo();
        ++undos;
      } else if (a < 5 && pipe.journal().redoCount() > 0) {
        pipe.redo();
        ++redos;
      } else if (a < 7) {
        settleSomething(t, *store, rng);
        ++settles;
      } else {
        edittest::randomStroke(pipe, rng, brush);
      }
      now += 1 + double(rng() % 4);
      if (i + 4 < actions) store->tick(now, pipe.inStroke());  // no save for the last few
    }
    store->flush();  // what the writer thread has queued reaches the disk
    ASSERT_TRUE(store->error().empty()) << store->error();
    EXPECT_GT(store->saves(), 1u) << "the test should cross autosaves";
    ASSERT_GT(store->recordsSinceSave(), 0u);
    EXPECT_GT(undos + redos, 0);
    EXPECT_GT(settles, 0);

    // The crash: the files as the running session leaves them.
    const Recovery rec = Recovery::inspect(files);
    ASSERT_EQ(rec.state(), Recovery::State::kRecoverable) << rec.message();
    EXPECT_EQ(rec.records(), store->recordsSinceSave());
    EXPECT_NE(rec.message().find(files.journal.string()), std::string::npos) << rec.message();
    const auto recovered = rec.recover();
    EXPECT_TRUE(sameHeights(recovered->heights(), t.heights())) << "seed " << seed;
    EXPECT_EQ(recovered->bounds().errorCodes(), t.bounds().errorCodes());
    EXPECT_EQ(recovered->bounds().radiusCodes(), t.bounds().radiusCodes());
    pipe.journal().setListener(nullptr);
  }
}

TEST(SessionStore, UndoIsJournaledAsTheHeightsBefore) {
  const fs::path dir = testkit::freshDir("session_undo");
  auto t = testkit::bumpyTerrain(6, 4, 3000.0);
  const std::vector<float> start(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  std::mt19937 rng(5);
  SessionStore store(t, SessionFiles::in(dir), {}, 0.0);
  pipe.journal().setListener(&store);
  edittest::randomStroke(pipe, rng, brush);
  edittest::randomStroke(pipe, rng, brush);
  pipe.undo();
  pipe.undo();
  ASSERT_TRUE(sameHeights(t.heights(), start));
  store.flush();
  const auto j = io::readStrokeJournal(dir / "planet.journal");
  ASSERT_EQ(j.records.size(), 4u);
  EXPECT_EQ(j.records[2].kind, io::JournalRecordKind::kUndo);
  // Recovery gives the planet as it is now: both strokes taken back.
  const Recovery rec = Recovery::inspect(SessionFiles::in(dir));
  ASSERT_EQ(rec.state(), Recovery::State::kRecoverable) << rec.message();
  EXPECT_TRUE(sameHeights(rec.recover()->heights(), start));
  pipe.redo();
  store.flush();
  EXPECT_TRUE(
      sameHeights(Recovery::inspect(SessionFiles::in(dir)).recover()->heights(), t.heights()));
  pipe.journal().setListener(nullptr);
}

TEST(SessionStore, AutosaveWaitsForTheIntervalAChangeAndTheEndOfAStroke) {
  const fs::path dir = testkit::freshDir("session_autosave");
  auto t = testkit::bumpyTerrain(6, 4, 3000.0);
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  SessionStore store(t, SessionFiles::in(dir), {60, true}, 100.0);
  pipe.journal().setListener(&store);
  EXPECT_EQ(store.saves(), 1u);  // the session starts with a save
  EXPECT_TRUE(sameHeights(io::readPlanetFile(dir / "planet.planet").heights, t.heights()));
  EXPECT_FALSE(store.tick(1000, false)) << "nothing changed: no save";
  const Eigen::Vector3d p = t.chart().position(10, 20, 0.0);
  pipe.beginStroke(brush, {p, 0});
  EXPECT_FALSE(store.tick(2000, true)) << "a stroke is open";
  pipe.endStroke();
  store.flush();
  EXPECT_EQ(store.recordsSinceSave(), 1u);
  EXPECT_FALSE(store.tick(100 + 59.9, false)) << "before the interval";
  EXPECT_TRUE(store.tick(2000, false));
  EXPECT_FALSE(store.tick(5000, false)) << "nothing changed since";
  store.flush();
  EXPECT_EQ(store.saves(), 2u);
  EXPECT_EQ(store.savesDone(), 2u);
  EXPECT_EQ(store.recordsSinceSave(), 0u);
  EXPECT_EQ(fs::file_size(dir / "planet.journal"), io::kStrokeJournalHeaderBytes);
  EXPECT_TRUE(sameHeights(io::readPlanetFile(dir / "planet.planet").heights, t.heights()));
  // After a save there is nothing to recover.
  EXPECT_EQ(Recovery::inspect(SessionFiles::in(dir)).state(), Recovery::State::kNone);
  pipe.journal().setListener(nullptr);
}

TEST(StrokeJournal, TornLastRecordAtEveryByteRecoversTheCompleteStrokes) {
  const fs::path dir = testkit::freshDir("session_torn");
  auto t = testkit::bumpyTerrain(6, 7, 3000.0);
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  std::mt19937 rng(9);
  auto store = std::make_unique<SessionStore>(t, SessionFiles::in(dir),
                                              session::SessionStoreOptions{0, false}, 0.0);
  pipe.journal().setListener(store.get());
  std::vector<std::vector<float>> states;
  for (int i = 0; i < 4; ++i) {
    edittest::randomStroke(pipe, rng, brush);
    states.emplace_back(t.heights().begin(), t.heights().end());
  }
  pipe.journal().setListener(nullptr);
  store->flush();
  const auto full = readAll(dir / "planet.journal");
  const auto whole = io::parseStrokeJournal(full, "j");
  ASSERT_EQ(whole.records.size(), 4u);
  ASSERT_TRUE(whole.warning.empty()) << whole.warning;
  std::size_t lastStart = io::kStrokeJournalHeaderBytes;
  for (int i = 0; i < 3; ++i)
    lastStart +=
        io::kStrokeJournalRecordOverhead + 8 * whole.records[std::size_t(i)].heights.size();
  ASSERT_LT(lastStart, full.size());

  for (std::size_t cut = lastStart; cut < full.size(); ++cut) {
    const auto j = io::parseStrokeJournal(std::span(full).first(cut), "planet.journal");
    ASSERT_EQ(j.records.size(), 3u) << "cut at " << cut;
    EXPECT_EQ(j.validBytes, lastStart);
    if (cut > lastStart) {
      EXPECT_NE(j.warning.find("planet.journal: record 3"), std::string::npos) << j.warning;
    } else {
      EXPECT_TRUE(j.warning.empty());
    }
  }
  // The same through the files, at a few places, with zeros or garbage where the write stopped.
  const std::size_t lastSize = full.size() - lastStart;
  for (std::size_t cut : {lastStart + 1, lastStart + 15, lastStart + 16, lastStart + lastSize / 2,
                          full.size() - 4, full.size() - 1}) {
    for (int garbage = 0; garbage < 2; ++garbage) {
      std::vector<unsigned char> b(full.begin(), full.begin() + std::ptrdiff_t(cut));
      if (garbage) b.resize(full.size(), 0xA5);
      writeAll(dir / "planet.journal", b);
      const Recovery rec = Recovery::inspect(SessionFiles::in(dir));
      ASSERT_EQ(rec.state(), Recovery::State::kRecoverable) << rec.message();
      EXPECT_EQ(rec.records(), 3u);
      EXPECT_NE(rec.message().find("ignored"), std::string::npos) << rec.message();
      EXPECT_TRUE(sameHeights(rec.recover()->heights(), states[2])) << "cut at " << cut;
    }
  }
  // A damaged record in the middle: the records before it, and a warning naming it.
  {
    std::vector<unsigned char> b = full;
    const std::size_t second = io::kStrokeJournalHeaderBytes + io::kStrokeJournalRecordOverhead +
                               8 * whole.records[0].heights.size();
    b[second + 20] ^= 0x40;
    const auto j = io::parseStrokeJournal(b, "planet.journal");
    EXPECT_EQ(j.records.size(), 1u);
    EXPECT_NE(j.warning.find("record 1"), std::string::npos) << j.warning;
    EXPECT_NE(j.warning.find("checksum"), std::string::npos) << j.warning;
  }
  // A damaged header is refused.
  {
    std::vector<unsigned char> b = full;
    b[17] ^= 1;
    EXPECT_THROW(io::parseStrokeJournal(b, "j"), core::InputError);
    EXPECT_THROW(io::parseStrokeJournal(std::span(full).first(10), "j"), core::InputError);
  }
}

TEST(Recovery, AnotherPlanetsJournalIsRefusedNamingTheFile) {
  const fs::path dir = testkit::freshDir("session_foreign");
  const SessionFiles files = SessionFiles::in(dir);
  auto t = testkit::bumpyTerrain(6, 4, 3000.0);
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  std::mt19937 rng(11);
  {
    SessionStore store(t, files, {0, true}, 0.0);
    pipe.journal().setListener(&store);
    edittest::randomStroke(pipe, rng, brush);
    edittest::randomStroke(pipe, rng, brush);
    pipe.journal().setListener(nullptr);
  }
  const auto journalBytes = readAll(files.journal);

  // Another planet in the planet file (same grid, other heights).
  io::savePlanet(testkit::bumpyTerrain(6, 5, 3000.0), files.planet);
  Recovery rec = Recovery::inspect(files);
  EXPECT_EQ(rec.state(), Recovery::State::kRefused);
  EXPECT_NE(rec.message().find(files.journal.string()), std::string::npos) << rec.message();
  EXPECT_NE(rec.message().find("another planet"), std::string::npos) << rec.message();
  EXPECT_THROW(rec.recover(), core::InputError);
  const fs::path aside = rec.setAside();
  EXPECT_EQ(aside, fs::path(files.journal.string() + ".refused"));
  EXPECT_TRUE(fs::exists(aside));
  EXPECT_FALSE(fs::exists(files.journal));

  // Another grid.
  writeAll(files.journal, journalBytes);
  io::savePlanet(testkit::bumpyTerrain(5, 4, 3000.0), files.planet);
  rec = Recovery::inspect(files);
  EXPECT_EQ(rec.state(), Recovery::State::kRefused);
  EXPECT_NE(rec.message().find("grid side 65"), std::string::npos) << rec.message();

  // No planet file at all.
  fs::remove(files.planet);
  rec = Recovery::inspect(files);
  EXPECT_EQ(rec.state(), Recovery::State::kRefused);
  EXPECT_NE(rec.message().find("does not exist"), std::string::npos) << rec.message();

  // The planet file saved after the strokes, the journal not yet started again (a crash between
  // the two steps of an autosave): nothing to recover, and nothing refused.
  io::savePlanet(t, files.planet);
  rec = Recovery::inspect(files);
  EXPECT_EQ(rec.state(), Recovery::State::kAlreadySaved) << rec.message();

  // Not a journal at all.
  writeAll(files.journal, std::vector<unsigned char>(100, 'x'));
  rec = Recovery::inspect(files);
  EXPECT_EQ(rec.state(), Recovery::State::kRefused);
  EXPECT_NE(rec.message().find("not a PlanetSculpt stroke journal"), std::string::npos)
      << rec.message();

  // No journal: nothing.
  fs::remove(files.journal);
  EXPECT_EQ(Recovery::inspect(files).state(), Recovery::State::kNone);
}

// The live app's wiring on the synthetic short scene: the sand displacement tool through the
// frame stepper (strokes in the undo journal, settling outside it, reported as
// StepResult::settled), an undo, autosaves on a frame clock; a crash after the last frame
// recovers the stepper's planet bit for bit.
TEST(SessionStore, DisplacedAndSettledSandThroughTheStepperRecoversBitForBit) {
  // Without autosave every record since the start is applied (settling interleaved with the
  // stroke's stamps); with it, the scene crosses an autosave at the stroke's end.
  for (const double autosave : {0.0, 4.0}) {
    const fs::path dir = testkit::freshDir("session_stepper" + std::to_string(int(autosave)));
    // Cells of about 20 km and a deep press: steep enough for the sand to slide.
    auto t = testkit::bumpyTerrain(10, 4, 3000.0);
    replay::ReplayOptions o = testkit::shortSceneOptions();
    o.tool = replay::ReplayTool::kDisplace;
    o.pressDepth = 40000;
    o.settling.maxStepsPerFrame = 1;  // settling goes on for frames after the stroke
    o.undo = true;
    tracking::FrameSource src(testkit::shortSceneVideo());
    replay::FrameStepper stepper(testkit::shortSceneCamera().forImageSize(src.size()), t, o);
    SessionStore store(t, SessionFiles::in(dir), {autosave, true}, 0.0);
    stepper.pipeline().journal().setListener(&store);
    cv::Mat image;
    int settledFrames = 0, saves = 0;
    while (src.read(image)) {
      const auto r = stepper.step(image, src.index(), src.index() / src.fps());
      if (!r.settled.empty()) {
        store.recordRegion(r.settled);
        ++settledFrames;
      }
      saves += store.tick(double(src.index()), stepper.pipeline().inStroke());
    }
    stepper.endStroke();
    // Frames with no marker: the sand goes on settling after the stroke.
    const cv::Mat blank(image.size(), image.type(), cv::Scalar::all(128));
    int settledAfter = 0;
    for (int f = 0; f < 4; ++f) {
      const auto r = stepper.step(blank, 50 + f, (50 + f) / src.fps());
      if (!r.settled.empty()) {
        store.recordRegion(r.settled);
        ++settledAfter;
      }
    }
    EXPECT_GT(settledAfter, 0);
    // A crash now: the stroke's vertices as they are (settled between its stamps).
    store.flush();
    if (store.recordsSinceSave() > 0) {
      const Recovery rec = Recovery::inspect(SessionFiles::in(dir));
      ASSERT_EQ(rec.state(), Recovery::State::kRecoverable) << rec.message();
      EXPECT_TRUE(sameHeights(rec.recover()->heights(), t.heights()))
          << "after the stroke, autosave " << autosave;
    }
    // Undo, redo, undo, and sand settling after each (a record after the last autosave).
    for (int k = 0; k < 3; ++k) {
      if (k == 1)
        stepper.pipeline().redo();
      else
        stepper.pipeline().undo();
      for (int f = 0; f < 2; ++f) {
        const auto r = stepper.step(image, 100 + 2 * k + f, (100 + 2 * k + f) / src.fps());
        if (!r.settled.empty()) store.recordRegion(r.settled);
      }
    }
    store.flush();
    ASSERT_TRUE(store.error().empty()) << store.error();
    EXPECT_GT(settledFrames, 3) << "the scene should settle sand";
    EXPECT_GE(stepper.summary().strokes, 1);
    EXPECT_EQ(saves, autosave > 0 ? 1 : 0);
    ASSERT_GT(store.recordsSinceSave(), 0u);
    // The crash: the files as they are now.
    const Recovery rec = Recovery::inspect(SessionFiles::in(dir));
    ASSERT_EQ(rec.state(), Recovery::State::kRecoverable) << rec.message();
    EXPECT_TRUE(sameHeights(rec.recover()->heights(), t.heights())) << "autosave " << autosave;
    stepper.pipeline().journal().setListener(nullptr);
  }
}
