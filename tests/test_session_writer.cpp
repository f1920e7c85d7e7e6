// The live session's writer thread (session/session_writer.hpp): saves in the background while
// strokes go on, and kills at every step of such a save (the writer held there while the files
// are copied: what a SIGKILL at that instant leaves) and at random instants of a real process.
// Each time, recovery gives one of the session's planets bit for bit: the one after the last
// record that reached the disk.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <random>
#include <thread>

#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "fresh_dir.hpp"
#include "io/planet_file.hpp"
#include "io/stroke_journal.hpp"
#include "session/heights_shadow.hpp"
#include "session/session_store.hpp"
#include "stress_util.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

extern char** environ;

using namespace ps;
namespace fs = std::filesystem;
using session::Recovery;
using session::SessionFiles;
using session::SessionStore;

namespace {

// A stroke from `rng` alone (no other random source), so a second run repeats it exactly.
void strokeFrom(edit::EditPipeline& pipe, std::mt19937& rng, edit::GaussianBrush& brush) {
  const auto& t = pipe.terrain();
  edit::BrushSettings s;
  s.radius = 200e3 + 50e3 * double(rng() % 6);
  s.sigma = 0.3;
  s.mode = edit::BrushMode(rng() % 2);
  s.strength = 100.0 + double(rng() % 2000);
  brush.setSettings(s);
  const int m = t.grid().m();
  const int u = 1 + int(rng() % unsigned(m - 2)), v = 2 + int(rng() % unsigned(m - 4));
  Eigen::Vector3d p = t.chart().position(u, v, 0.0);
  pipe.beginStroke(brush, {p, 0});
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d d(double(int(rng() % 200) - 100), double(int(rng() % 200) - 100),
                            double(int(rng() % 200) - 100));
    p = (p + t.chart().sphereRadius() * 0.001 * d).normalized() * t.chart().sphereRadius();
    pipe.moveTo({p, 0.05});
  }
  pipe.endStroke();
}

// The planet a kill leaves behind: the planet file, with the journal applied when it holds
// records for it.
std::vector<float> recoveredHeights(const SessionFiles& files, std::string& how) {
  const Recovery rec = Recovery::inspect(files);
  how = rec.message();
  if (rec.state() == Recovery::State::kRefused) return {};
  if (rec.state() == Recovery::State::kRecoverable) {
    const auto t = rec.recover();
    return {t->heights().begin(), t->heights().end()};
  }
  return io::readPlanetFile(files.planet).heights;
}

SessionFiles copyOf(const SessionFiles& files, const fs::path& dir) {
  fs::create_directories(dir);
  const SessionFiles to = SessionFiles::in(dir);
  fs::copy_file(files.planet, to.planet, fs::copy_options::overwrite_existing);
  fs::copy_file(files.journal, to.journal, fs::copy_options::overwrite_existing);
  return to;
}

}  // namespace

TEST(HeightsShadow, FollowsEditsInBoundedCopiesAndEqualsTheTerrainWhenCurrent) {
  auto t = testkit::bumpyTerrain(7, 3, 3000.0);
  session::HeightsShadow shadow(t);
  EXPECT_TRUE(shadow.current());
  EXPECT_TRUE(edittest::sameBits(shadow.heights(), t.heights()));
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  std::mt19937 rng(4);
  for (int round = 0; round < 20; ++round) {
    strokeFrom(pipe, rng, brush);
    if (round % 5 == 4) pipe.undo();
    shadow.follow(t);
    EXPECT_FALSE(shadow.current() && !edittest::sameBits(shadow.heights(), t.heights()));
    // A few rows per call: several calls to catch up, and equal only then.
    std::size_t calls = 0;
    while (!shadow.current()) {
      shadow.catchUp(t, 4 * sizeof(float) * std::size_t(t.grid().side()));
      ++calls;
    }
    EXPECT_GT(calls, 0u);
    ASSERT_TRUE(edittest::sameBits(shadow.heights(), t.heights())) << "round " << round;
  }
  // More changes than the terrain keeps: every row is copied again, and the copy is right.
  for (std::size_t k = 0; k <= terrain::Terrain::kKeptChanges; ++k) {
    auto h = t.mutableHeights();
    const int u = 1 + int(k % 100), v = 3 + int(k % 97);
    h[t.grid().index(u, v)] += 1.0f;
    t.commitEdit(terrain::VertexBox{u, u, v, v});
  }
  shadow.follow(t);
  EXPECT_EQ(shadow.pendingRows(), std::size_t(t.grid().side()));
  shadow.catchUp(t, SIZE_MAX);
  EXPECT_TRUE(edittest::sameBits(shadow.heights(), t.heights()));
}

// The writer is held at every step of a background save (checksum pieces, write pieces, the
// mark, the planet file replaced, the journal restarted); there the files are copied, a stroke
// is made (queued behind the save), and the writer goes on. Every copy recovers the planet
// after exactly the records the writer had written by then.
TEST(SessionWriter, KillAtEveryStepOfABackgroundSaveRecoversBitForBit) {
  const fs::path dir = testkit::freshDir("writer_steps");
  auto t = testkit::bumpyTerrain(8, 6, 3000.0);
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  std::mt19937 rng(12);
  // Records not flushed (a killed process loses nothing written); 257² heights in 64 KiB
  // steps: 5 checksum and 5 write steps.
  session::SessionStoreOptions o{0, false};
  o.writer.saveStepBytes = 64 << 10;
  const SessionFiles files = SessionFiles::in(dir / "live");
  fs::create_directories(files.planet.parent_path());
  SessionStore store(t, files, o, 0.0);
  pipe.journal().setListener(&store);
  // states[n]: the planet after the session's n-th record.
  std::vector<std::vector<float>> states{{t.heights().begin(), t.heights().end()}};
  auto stroke = [&] {
    strokeFrom(pipe, rng, brush);
    states.emplace_back(t.heights().begin(), t.heights().end());
  };
  for (int i = 0; i < 3; ++i) stroke();

  std::mutex m;
  std::condition_variable cv;
  bool held = false;
  std::vector<session::SaveStep> steps;
  store.writer().setStepHook([&](session::SaveStep s) {
    std::unique_lock lock(m);
    steps.push_back(s);
    held = true;
    cv.notify_all();
    cv.wait(lock, [&] { return !held; });
  });
  for (int save = 0; save < 2; ++save) {
    store.requestSave();
    ASSERT_TRUE(store.tick(1.0 + save, false));
    int kills = 0;
    for (;;) {
      std::unique_lock lock(m);
      // The end of the save is not signalled through `cv`: looked at every millisecond.
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (!held && store.saving() && std::chrono::steady_clock::now() < deadline)
        cv.wait_for(lock, std::chrono::milliseconds(1));
      if (!held && store.saving()) FAIL() << "the writer neither held nor finished";
      if (!held) break;
      // A kill here: the files as they are while the writer is held.
      const std::size_t written = store.writerStats().records;
      const SessionFiles image =
          copyOf(files, dir / ("kill-" + std::to_string(save) + "-" + std::to_string(kills)));
      std::string how;
      const auto got = recoveredHeights(image, how);
      ASSERT_LT(written, states.size());
      EXPECT_TRUE(edittest::sameBits(got, states[written]))
          << "save " << save << ", kill " << kills << " (step " << int(steps.back())
          << "), records on disk " << written << ": " << how;
      ++kills;
      stroke();  // queued behind the save, written between its steps
      if (kills % 4 == 0) pipe.undo(), states.emplace_back(t.heights().begin(), t.heights().end());
      store.tick(2.0 + save, false);  // no second save while one runs
      held = false;
      cv.notify_all();
    }
    EXPECT_GE(kills, 13);
  }
  for (auto s :
       {session::SaveStep::kMarked, session::SaveStep::kReplaced, session::SaveStep::kRestarted})
    EXPECT_EQ(std::count(steps.begin(), steps.end(), s), 2) << int(s);
  store.writer().setStepHook(nullptr);
  store.flush();
  EXPECT_EQ(store.savesDone(), 3u);
  EXPECT_TRUE(store.error().empty()) << store.error();
  std::string how;
  EXPECT_TRUE(edittest::sameBits(recoveredHeights(files, how), t.heights())) << how;
  // The strokes made during the save are in the journal that continues it.
  EXPECT_GT(Recovery::inspect(files).records(), 0u);
  EXPECT_EQ(Recovery::inspect(files).records(), store.recordsSinceSave());
  pipe.journal().setListener(nullptr);
}

// The child of the next test: a session on a 1025² planet saving again as soon as a save ends,
// stroking as fast as it can, until it is killed. Skipped unless run by that test.
TEST(SessionWriterChild, StrokesAndSavesUntilKilled) {
  const char* dir = std::getenv("PS_WRITER_CHILD_DIR");
  const char* seed = std::getenv("PS_WRITER_CHILD_SEED");
  const char* killAt = std::getenv("PS_WRITER_CHILD_KILL_AT");
  if (!dir || !seed || !killAt) GTEST_SKIP() << "run by SessionWriter.SigkillDuringBackgroundSaves";
  const int strokesBeforeKill = std::atoi(killAt);
  auto t = testkit::bumpyTerrain(10, 3, 3000.0);
  edit::EditPipeline pipe(t);
  edit::GaussianBrush brush;
  std::mt19937 rng(std::uint32_t(std::atoi(seed)));
  session::SessionStoreOptions o{0.01, true};
  o.writer.saveStepBytes = 256 << 10;
  SessionStore store(t, SessionFiles::in(dir), o, 0.0);
  pipe.journal().setListener(&store);
  std::ofstream(fs::path(dir) / "started") << "1";
  // SIGKILL from the session's own thread after the parent's number of strokes: wherever the
  // writer thread is then (appending, in a save's step, renaming) is the instant of the kill.
  for (int i = 0; i < 100000; ++i) {
    if (i == strokesBeforeKill) ::raise(SIGKILL);
    strokeFrom(pipe, rng, brush);
    store.tick(double(i), false);
  }
  pipe.journal().setListener(nullptr);
}

TEST(SessionWriter, SigkillDuringBackgroundSavesRecoversAPlanetTheSessionHad) {
  const fs::path dir = testkit::freshDir("writer_sigkill");
  std::mt19937 pick(2026);
  int recoveredFromMark = 0, killedWhileSaving = 0;
  // Three kills at random instants; one under the sanitizers, where the child's session is
  // several times slower (the optimised pass makes all three).
  const int runs = testkit::underAsan() ? 1 : 3;
  for (int run = 0; run < runs; ++run) {
    const fs::path out = dir / std::to_string(run);
    fs::create_directories(out);
    const std::string seed = std::to_string(100 + run);
    const std::string envDir = "PS_WRITER_CHILD_DIR=" + out.string(),
                      envSeed = "PS_WRITER_CHILD_SEED=" + seed,
                      envKill = "PS_WRITER_CHILD_KILL_AT=" + std::to_string(20 + pick() % 400);
    std::vector<char*> env;
    for (char** e = environ; *e; ++e) env.push_back(*e);
    env.push_back(const_cast<char*>(envDir.c_str()));
    env.push_back(const_cast<char*>(envSeed.c_str()));
    env.push_back(const_cast<char*>(envKill.c_str()));
    env.push_back(nullptr);
    std::string exe = fs::read_symlink("/proc/self/exe").string(),
                filter = "--gtest_filter=SessionWriterChild.StrokesAndSavesUntilKilled";
    char* argv[] = {exe.data(), filter.data(), nullptr};
    pid_t pid = 0;
    ASSERT_EQ(::posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv, env.data()), 0);
    // The child kills itself after a random number of strokes (its first save is done then).
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(fs::exists(out / "started")) << "the child session did not start";
    ASSERT_TRUE(WIFSIGNALED(status)) << "the child ended before the kill; status " << status;

    const SessionFiles files = SessionFiles::in(out);
    for (const auto& e : fs::directory_iterator(out))
      killedWhileSaving += e.path().filename().string().starts_with(".planet.planet.tmp-");
    const auto j = io::readStrokeJournal(files.journal);
    for (const auto& r : j.records) recoveredFromMark += r.kind == io::JournalRecordKind::kSaveMark;
    std::string how;
    const auto got = recoveredHeights(files, how);
    ASSERT_FALSE(got.empty()) << "refused: " << how;
    // The same session again, in this process, until it meets the recovered planet.
    auto t = testkit::bumpyTerrain(10, 3, 3000.0);
    edit::EditPipeline pipe(t);
    edit::GaussianBrush brush;
    std::mt19937 rng(std::uint32_t(std::atoi(seed.c_str())));
    const std::uint32_t want = io::heightsChecksum(got);
    int strokes = 0;
    while (io::heightsChecksum(t.heights()) != want && strokes < 20000) {
      strokeFrom(pipe, rng, brush);
      ++strokes;
    }
    ASSERT_TRUE(edittest::sameBits(got, t.heights()))
        << "run " << run << ": the recovered planet is none of the session's (" << how << ")";
    EXPECT_GT(strokes, 0) << how;
  }
  // Marks are left in the journal by saves still running or not yet restarted at the kill.
  RecordProperty("save_marks_seen", recoveredFromMark);
  std::cout << "kills while a planet file was written: " << killedWhileSaving << " of " << runs
            << "; save marks in the killed sessions' journals: " << recoveredFromMark << "\n";
}

TEST(StrokeJournal, SaveMarksRoundTripAndABadOneEndsTheReadableRecords) {
  io::JournalBase base{65, 6.4e6, 0x1234u, 3};
  std::vector<unsigned char> b = io::encodeJournalHeader(base);
  const std::vector<io::JournalHeight> h{{5, 1.5f}, {70, -2.0f}};
  io::encodeJournalRecord(io::JournalRecordKind::kStroke, 0, h, b);
  io::encodeJournalMark({0xCAFEF00Du, 1, 4}, 1, b);
  io::encodeJournalRecord(io::JournalRecordKind::kUndo, 2, h, b);
  const auto j = io::parseStrokeJournal(b, "j");
  ASSERT_EQ(j.records.size(), 3u) << j.warning;
  EXPECT_EQ(j.records[1].kind, io::JournalRecordKind::kSaveMark);
  EXPECT_EQ(j.records[1].mark, (io::JournalMark{0xCAFEF00Du, 1, 4}));
  EXPECT_TRUE(j.records[1].heights.empty());
  EXPECT_EQ(io::heightRecordsFrom(j, 0), 2u);
  EXPECT_EQ(io::heightRecordsFrom(j, 1), 1u);
  // A mark whose resume point lies after itself is not one the writer writes.
  std::vector<unsigned char> bad = io::encodeJournalHeader(base);
  io::encodeJournalRecord(io::JournalRecordKind::kStroke, 0, h, bad);
  io::encodeJournalMark({1, 2, 4}, 1, bad);
  const auto k = io::parseStrokeJournal(bad, "j");
  EXPECT_EQ(k.records.size(), 1u);
  EXPECT_NE(k.warning.find("save mark"), std::string::npos) << k.warning;
}
