// A live session's settings timeline (replay/session_timeline.hpp): a session scripted through
// the live app's path (FrameStepper + SettingsControl, the frames recorded by FrameRecorder, the
// changes by TimelineWriter) replays from its files to the same planet, bit for bit, and not
// without its sidecar; a bad sidecar is refused naming the file and the line.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <sstream>

#include "core/input_error.hpp"
#include "fresh_dir.hpp"
#include "replay/replay.hpp"
#include "replay/session_timeline.hpp"
#include "sand/material.hpp"
#include "session/frame_recorder.hpp"
#include "short_scene.hpp"
#include "test_terrains.hpp"
#include "tracking/video.hpp"

using namespace ps;
using replay::SettingsControl;

namespace {

bool sameHeights(const terrain::Terrain& a, const terrain::Terrain& b) {
  return a.heights().size() == b.heights().size() &&
         std::memcmp(a.heights().data(), b.heights().data(), a.heights().size() * sizeof(float)) ==
             0;
}

// What the user does after a window frame: (frame, action), applied once that frame is stepped,
// as the live app applies the panel after the frame it drew.
using Script = std::vector<std::pair<int, std::function<void(SettingsControl&)>>>;

// The live app's frame loop without the window: record the frame, step it, apply the panel.
// `clock` gives a frame's time from its index: the video's (index / fps) by default, or a
// camera's irregular wall clock.
std::filesystem::path recordSession(const std::filesystem::path& dir, terrain::Terrain& planet,
                                    const Script& script,
                                    std::function<double(int, double)> clock = {},
                                    replay::ReplayOptions options = testkit::shortSceneOptions()) {
  if (!clock) clock = [](int index, double fps) { return index / fps; };
  tracking::FrameSource src(testkit::shortSceneVideo());
  const auto calib = testkit::shortSceneCamera().forImageSize(src.size());
  options.undo = true;  // as live
  replay::FrameStepper stepper(calib, planet, options);
  SettingsControl control(stepper);
  session::FrameRecorder recorder;
  replay::TimelineWriter timeline;
  const auto video = dir / "session.mkv";
  recorder.start(video, src.fps());
  timeline.open(replay::sessionSidecarPath(video),
                replay::SessionStart::of(planet, "", planet.grid().side(), 1, calib, "synthetic",
                                         stepper.options(), src.fps(), 0),
                control.settings());
  control.setWriter(&timeline);
  cv::Mat image;
  while (src.read(image)) {
    const double time = clock(src.index(), src.fps());
    recorder.write(image);
    timeline.frameRecorded(time);
    stepper.step(image, src.index(), time);
    for (const auto& [frame, action] : script)
      if (frame == src.index()) action(control);
  }
  // Changes after the video's last frame (entries at frame == frame count) matter too.
  for (const auto& [frame, action] : script)
    if (frame == timeline.frames()) action(control);
  stepper.endStroke();
  control.setWriter(nullptr);
  timeline.close();
  EXPECT_EQ(recorder.stop(), 12);
  return video;
}

Script changesOfEveryKind() {
  auto with = [](std::function<void(replay::SessionSettings&)> f) {
    return [f](SettingsControl& c) {
      auto s = c.settings();
      f(s);
      c.apply(s);
    };
  };
  return {
      {2, with([](auto& s) { s.brush.radius *= 1.6; })},
      {3, with([](auto& s) { s.brush.strength *= 2.5; })},
      {4, with([](auto& s) { s.brush.mode = edit::BrushMode::kLower; })},
      {5, with([](auto& s) { s.planetRadius *= 1.1f; })},
      {6, [](SettingsControl& c) { c.undo(); }},
      {7, with([](auto& s) { s.spinDeg = 30; })},
      {8, with([](auto& s) { s.tool = replay::ReplayTool::kDisplace; })},
      {9, [](SettingsControl& c) { c.undo(); }},
      {9, [](SettingsControl& c) { c.redo(); }},
      {12, [](SettingsControl& c) { c.undo(); }},  // after the last frame (11)
  };
}

replay::ReplaySummary replayFiles(const std::filesystem::path& video, terrain::Terrain& planet,
                                  const replay::SessionTimeline* timeline) {
  tracking::FrameSource src(video.string());
  std::ostringstream log;
  return replay::runReplay(src, testkit::shortSceneCamera(), planet, testkit::shortSceneOptions(),
                           log, nullptr, {}, {}, timeline);
}

// A sidecar at `path` holding only the writer's header for a session of the short scene's camera
// and options on `planet`.
void writeSidecarHeader(const std::filesystem::path& path, const terrain::Terrain& planet) {
  replay::TimelineWriter w;
  w.open(path,
         replay::SessionStart::of(planet, "", planet.grid().side(), 1, testkit::shortSceneCamera(),
                                  "synthetic", testkit::shortSceneOptions(), 30, 0),
         replay::SessionSettings::of(testkit::shortSceneOptions()));
}

std::filesystem::path sidecarWith(const std::filesystem::path& dir, const std::string& name,
                                  const std::vector<std::string>& lines, bool lastNewline = true) {
  // A real header from the writer, then the given lines.
  const auto path = dir / name;
  writeSidecarHeader(path, testkit::bumpyTerrain(5, 4, 3000.0));
  std::ofstream f(path, std::ios::app);
  for (std::size_t i = 0; i < lines.size(); ++i)
    f << lines[i] << (i + 1 < lines.size() || lastNewline ? "\n" : "");
  return path;
}

// Writes `to`, the header line of the sidecar `from` without `field` (a sidecar written before
// that field was); false when the header has no such field.
bool headerWithout(const std::filesystem::path& from, const std::string& field,
                   const std::filesystem::path& to) {
  std::ifstream in(from);
  std::string header;
  std::getline(in, header);
  const auto at = header.find(field);
  if (at == std::string::npos) return false;
  header.erase(at, field.size());
  std::ofstream(to) << header << "\n";
  return true;
}

void expectRefused(const std::filesystem::path& path, const std::string& where,
                   const std::string& what) {
  try {
    replay::readSessionTimeline(path);
    ADD_FAILURE() << path << " was read";
  } catch (const core::InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path.string() + where), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
  }
}

// A session of `script` recorded into a fresh folder `name` on the sessions' planet (bumpy, 129^2):
// the planet it started from, the planet it left, its video.
struct Recorded {
  std::filesystem::path dir;
  terrain::Terrain start, live;
  std::filesystem::path video;
};

Recorded recordOnTheSessionsPlanet(const std::string& name, const Script& script) {
  Recorded r{testkit::freshDir(name),
             testkit::bumpyTerrain(7, 4, 3000.0),
             testkit::bumpyTerrain(7, 4, 3000.0),
             {}};
  r.video = recordSession(r.dir, r.live, script);
  return r;
}

}  // namespace

TEST(SessionTimeline, ScriptedLiveSessionReplaysFromItsFilesBitForBit) {
  auto [dir, start, live, video] =
      recordOnTheSessionsPlanet("timeline_replay", changesOfEveryKind());
  ASSERT_FALSE(sameHeights(live, start)) << "the session sculpted nothing";

  const auto timeline = replay::readSessionTimeline(replay::sessionSidecarPath(video));
  EXPECT_TRUE(timeline.warning.empty()) << timeline.warning;
  // One line per change and per undo / redo.
  ASSERT_EQ(timeline.entries.size(), 10u);
  EXPECT_EQ(timeline.entries.front().frame, 3);  // changed after frame 2: applies from frame 3
  EXPECT_EQ(timeline.entries[4].event, "undo");
  EXPECT_EQ(timeline.entries[8].event, "redo");
  EXPECT_EQ(timeline.entries.back().event, "undo");
  EXPECT_EQ(timeline.entries.back().frame, 12);
  EXPECT_EQ(timeline.entries.back().settings.tool, replay::ReplayTool::kDisplace);

  auto replayed = start;
  replay::checkSessionStart(timeline, replayed,
                            testkit::shortSceneCamera().forImageSize({320, 240}));
  const auto s = replayFiles(video, replayed, &timeline);
  EXPECT_EQ(s.frames, 12);
  EXPECT_EQ(s.sessionChanges, 10);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  EXPECT_GE(s.strokes, 5);
  EXPECT_TRUE(sameHeights(replayed, live)) << "the replay sculpted another planet";

  // Without the sidecar the same frames sculpt another planet: the timeline is what matters.
  auto plain = start;
  replayFiles(video, plain, nullptr);
  EXPECT_FALSE(sameHeights(plain, live));
}

TEST(SessionTimeline, CameraClockIsRecordedAndReplayedWithARateBrush) {
  // A camera's frames come at irregular times; the One Euro filters and a rate brush (metres
  // per second) depend on them, so the sidecar carries each frame's time.
  const auto dir = testkit::freshDir("timeline_clock");
  auto options = testkit::shortSceneOptions();
  options.brush.rate = true;
  options.brush.strength = 20000;  // m/s
  auto live = testkit::bumpyTerrain(7, 4, 3000.0);
  const auto start = live;
  const auto video = recordSession(
      dir, live, {}, [](int i, double fps) { return 0.5 + i / fps * 1.3 + 0.004 * (i % 3); },
      options);
  const auto path = replay::sessionSidecarPath(video);
  const auto timeline = replay::readSessionTimeline(path);
  ASSERT_EQ(timeline.times.size(), 12u);
  EXPECT_DOUBLE_EQ(timeline.timeOf(0), 0.5);
  EXPECT_EQ(timeline.settings.brush.rate, true);
  auto replayed = start;
  replayFiles(video, replayed, &timeline);
  EXPECT_TRUE(sameHeights(replayed, live));

  // The same sidecar without its time lines: the replay steps at frame / fps and differs.
  {
    std::ifstream in(path);
    std::ofstream out(dir / "untimed.jsonl");
    for (std::string l; std::getline(in, l);)
      if (l.find("\"time_s\"") == std::string::npos) out << l << "\n";
  }
  const auto untimed = replay::readSessionTimeline(dir / "untimed.jsonl");
  EXPECT_TRUE(untimed.times.empty());
  auto atNominalRate = start;
  replayFiles(video, atNominalRate, &untimed);
  EXPECT_FALSE(sameHeights(atNominalRate, live));
}

TEST(SessionTimeline, ConstantSessionWritesOnlyItsHeaderAndReplaysAsBefore) {
  const auto [dir, start, live, video] = recordOnTheSessionsPlanet("timeline_constant", {});
  const auto timeline = replay::readSessionTimeline(replay::sessionSidecarPath(video));
  EXPECT_TRUE(timeline.entries.empty());
  auto with = start, without = start;
  replayFiles(video, with, &timeline);
  replayFiles(video, without, nullptr);
  EXPECT_TRUE(sameHeights(with, live));
  EXPECT_TRUE(sameHeights(without, live));
}

TEST(SessionTimeline, UndoOfAStrokeBeforeTheRecordingIsAWarningNamingTheLine) {
  // (A Ctrl+R recording that undoes a stroke made before it started.)
  const auto [dir, start, live, video] = recordOnTheSessionsPlanet("timeline_refused", {});
  const auto path = replay::sessionSidecarPath(video);
  std::ofstream(path, std::ios::app) << R"({"frame": 1, "event": "undo"})"
                                     << "\n";
  const auto timeline = replay::readSessionTimeline(path);
  auto replayed = start;
  const auto s = replayFiles(video, replayed, &timeline);
  EXPECT_EQ(s.frames, 12);
  EXPECT_EQ(s.sessionChanges, 0);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find(path.string() + ":2: undo at frame 1 refused"), std::string::npos)
      << s.warnings[0];
  EXPECT_TRUE(sameHeights(replayed, live));  // nothing to undo: the frames sculpt as recorded
}

TEST(SessionTimeline, AnotherStartPlanetOrCalibrationIsRefusedNamingTheSidecar) {
  const auto recorded = recordOnTheSessionsPlanet("timeline_start", {});
  const auto& video = recorded.video;
  const auto path = replay::sessionSidecarPath(video);
  const auto timeline = replay::readSessionTimeline(path);
  const auto calib = testkit::shortSceneCamera().forImageSize({320, 240});
  auto other = testkit::bumpyTerrain(7, 5, 3000.0);
  try {
    replay::checkSessionStart(timeline, other, calib);
    ADD_FAILURE() << "another planet was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string() + ":1: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("another planet"), std::string::npos) << e.what();
  }
  auto same = testkit::bumpyTerrain(7, 4, 3000.0);
  auto otherCalib = calib;
  otherCalib.K(0, 0) *= 1.01;
  EXPECT_THROW(replay::checkSessionStart(timeline, same, otherCalib), core::InputError);
  EXPECT_NO_THROW(replay::checkSessionStart(timeline, same, calib));
}

TEST(SessionTimeline, TheSandsMaterialIsRecordedReplayedAndSettlesAsChosen) {
  // The displacement tool from frame 1, sand or pebbles (a chosen material is a settings change
  // of its own, recorded like the others).
  auto session = [](const std::string& name, bool pebbles) {
    Script script = {{1, [pebbles](SettingsControl& c) {
                        auto s = c.settings();
                        s.tool = replay::ReplayTool::kDisplace;
                        // Deep enough for walls steeper than sand holds on 313 km cells.
                        s.displace.radius = 800e3;
                        s.pressDepth = 250e3;
                        if (pebbles) s.displace.material = sand::Material::pebbles();
                        c.apply(s);
                      }}};
    return recordOnTheSessionsPlanet(name, script);
  };
  auto sand = session("timeline_sand", false);
  auto pebbles = session("timeline_pebbles", true);
  ASSERT_FALSE(sameHeights(sand.live, sand.start)) << "the session pressed nothing";
  // Sand slides down to 30 degrees, pebbles hold 60: the same strokes leave other heights.
  EXPECT_FALSE(sameHeights(sand.live, pebbles.live));

  const auto timeline = replay::readSessionTimeline(replay::sessionSidecarPath(pebbles.video));
  ASSERT_EQ(timeline.entries.size(), 1u);
  EXPECT_EQ(timeline.entries[0].settings.displace.material, sand::Material::pebbles());
  auto replayed = pebbles.start;
  const auto s = replayFiles(pebbles.video, replayed, &timeline);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  EXPECT_TRUE(sameHeights(replayed, pebbles.live)) << "the replay pressed another planet";

  // A sidecar from before materials were recorded names none: its sand was sand.
  const auto old = pebbles.dir / "old.jsonl";
  ASSERT_TRUE(
      headerWithout(replay::sessionSidecarPath(pebbles.video), "\"material\":\"sand\",", old));
  EXPECT_EQ(replay::readSessionTimeline(old).settings.displace.material, sand::Material::sand());
}

TEST(SessionTimeline, BadSidecarsAreRefusedNamingFileAndLine) {
  const auto dir = testkit::freshDir("timeline_bad");
  expectRefused(sidecarWith(dir, "json.jsonl", {R"({"frame": 3, "sigma": 0.2})", "{nope"}),
                ":3: ", "not JSON");
  expectRefused(sidecarWith(dir, "field.jsonl", {R"({"frame": 3, "colour": 1})"}),
                ":2: ", "unknown field \"colour\"");
  expectRefused(sidecarWith(dir, "type.jsonl", {R"({"frame": 3, "strength_m": "lots"})"}),
                ":2: ", "\"strength_m\" is not a number");
  expectRefused(sidecarWith(dir, "value.jsonl", {R"({"frame": 3, "brush_radius_m": -5})"}),
                ":2: ", "radius");
  expectRefused(sidecarWith(dir, "material.jsonl", {R"({"frame": 3, "material": "clay"})"}),
                ":2: ", "\"material\" material 'clay' is not one of sand, mud, pebbles");
  expectRefused(sidecarWith(dir, "order.jsonl",
                            {R"({"frame": 5, "sigma": 0.2})", R"({"frame": 4, "sigma": 0.3})"}),
                ":3: ", "comes after frame 5");
  expectRefused(sidecarWith(dir, "frame.jsonl", {R"({"sigma": 0.2})"}), ":2: ", "\"frame\"");
  expectRefused(sidecarWith(dir, "event.jsonl", {R"({"frame": 2, "event": "jump"})"}),
                ":2: ", "\"event\"");
  expectRefused(sidecarWith(dir, "time.jsonl", {R"({"frame": 2, "time_s": -1})"}),
                ":2: ", "\"time_s\"");
  expectRefused(sidecarWith(dir, "blank.jsonl", {"", R"({"frame": 2, "sigma": 0.2})"}),
                ":2: ", "empty line");
  {
    // A header field out of its type's range.
    const auto good = sidecarWith(dir, "range-src.jsonl", {});
    std::ifstream in(good);
    std::string header;
    std::getline(in, header);
    const auto at = header.find("\"undo_steps\":0");
    ASSERT_NE(at, std::string::npos);
    header.replace(at, 14, "\"undo_steps\":-3");
    const auto p = dir / "range.jsonl";
    std::ofstream(p) << header << "\n";
    expectRefused(p, ":1: ", "\"undo_steps\" is out of range");
    header.replace(at, 15, "\"undo_steps\":0");
    header.replace(header.find("\"touch_m\":"), 10, "\"touch_m\":-9");
    std::ofstream(p) << header << "\n";
    expectRefused(p, ":1: ", "touch distance");  // a marker option a replay could not use
  }
  {
    const auto p = dir / "header.jsonl";
    std::ofstream(p) << R"({"frame": 0, "sigma": 0.2})"
                     << "\n";
    expectRefused(p, ":1: ", "not a session sidecar");
  }
  {
    const auto p = dir / "empty.jsonl";
    std::ofstream{p};
    expectRefused(p, ": ", "empty");
  }
  expectRefused(dir / "missing.jsonl", ": ", "cannot read");
}

TEST(SessionTimeline, DamagedSidecarsAreReadOrRefusedNeverAnythingElse) {
  // Bytes flipped, inserted and cut from a real sidecar: every result is a timeline or an
  // InputError naming the file (deterministic mutations, no fuzzer needed to run it).
  const auto dir = testkit::freshDir("timeline_mutate");
  const auto p =
      sidecarWith(dir, "good.jsonl",
                  {R"({"frame": 3, "sigma": 0.2})", R"({"frame": 4, "event": "undo"})",
                   R"({"frame": 5, "time_s": 0.25})", R"({"frame": 6, "tool": "displace"})"});
  std::ifstream in(p, std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(replay::parseSessionTimeline(good, p).entries.size(), 3u);
  std::mt19937 rng(7);
  const std::string alphabet = "{}[]\":,0123456789-.eE \ntruefalsnul\\x";
  int read = 0, refused = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string text = good;
    const int edits = 1 + int(rng() % 3);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = rng() % text.size();
      switch (rng() % 4) {
        case 0:
          text[at] = alphabet[rng() % alphabet.size()];
          break;
        case 1:
          text.insert(at, 1, alphabet[rng() % alphabet.size()]);
          break;
        case 2:
          text.erase(at, 1 + rng() % 8);
          break;
        default:
          text.resize(at);
          break;
      }
    }
    try {
      replay::parseSessionTimeline(text, p);
      ++read;
    } catch (const core::InputError& e) {
      ++refused;
      EXPECT_EQ(std::string(e.what()).rfind(p.string() + ":", 0), 0u) << e.what();
    }
  }
  EXPECT_GT(read, 0);
  EXPECT_GT(refused, 0);
}

TEST(SessionTimeline, TornLastLineOfACrashIsIgnoredWithAWarning) {
  const auto dir = testkit::freshDir("timeline_torn");
  const auto p =
      sidecarWith(dir, "torn.jsonl",
                  {R"({"frame": 3, "sigma": 0.2})", R"({"frame": 4, "strength_m": 7)"}, false);
  const auto t = replay::readSessionTimeline(p);
  ASSERT_EQ(t.entries.size(), 1u);
  EXPECT_DOUBLE_EQ(t.entries[0].settings.brush.sigma, 0.2);
  EXPECT_NE(t.warning.find(p.string() + ":3: "), std::string::npos) << t.warning;
}

// A sidecar names the start planet's chart (lat-long or octahedral alike); one written before
// sidecars named it reads as lat-long, the chart every recording was made on then, and says it
// named none (the replay tells the user so; app/replay_job.cpp).
TEST(SessionTimeline, SidecarsNameTheirChartAndOnesThatNameNoneAreLatLong) {
  const auto dir = testkit::freshDir("timeline_chart");
  auto write = [&](const terrain::Terrain& planet, const std::string& name) {
    const auto path = dir / name;
    writeSidecarHeader(path, planet);
    return path;
  };
  const auto latlong = replay::readSessionTimeline(write(testkit::bumpyTerrain(5, 4), "ll.jsonl"));
  EXPECT_EQ(latlong.start.chart, "latlong");
  EXPECT_TRUE(latlong.start.chartNamed);
  const auto octaPath = write(testkit::bumpyOctahedralTerrain(5, 4), "octa.jsonl");
  const auto octa = replay::readSessionTimeline(octaPath);
  EXPECT_EQ(octa.start.chart, "octahedral");
  EXPECT_TRUE(octa.start.chartNamed);
  // The same header without its "chart" field: an old sidecar.
  const auto old = dir / "old.jsonl";
  ASSERT_TRUE(headerWithout(octaPath, "\"chart\":\"octahedral\",", old));
  const auto before = replay::readSessionTimeline(old);
  EXPECT_EQ(before.start.chart, "latlong");
  EXPECT_FALSE(before.start.chartNamed);
  EXPECT_EQ(before.start.gridSide, octa.start.gridSide);
}
