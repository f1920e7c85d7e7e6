// `planetsculpt bench track`: marker tracking against synthetic ground truth (tracking/synth.hpp).
// Per detector configuration: time per frame (detection + poses + filters + tip, one thread),
// tool tip error in the planet's frame (filtered and raw), pose flips (filtered poses more than
// 15 degrees off) and how often the control vertex on a 2049^2 planet lands within 3 mm of the
// ground truth's in touching frames.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "app/build_paths.hpp"
#include "app/progress.hpp"
#include "bench/bench.hpp"
#include "bench/bench_track_board.hpp"
#include "bench/bench_util.hpp"
#include "core/latlong_chart.hpp"
#include "edit/control_vertex.hpp"
#include "tracking/detector.hpp"
#include "tracking/synth.hpp"
#include "tracking/tracker.hpp"

namespace ps::bench {

namespace {

// CPU time of this thread (ms): on a shared machine, closer to "one core's time" than the wall
// clock, which also counts waiting for a core.
double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

struct Recording {
  std::string scene;
  tracking::SynthScript script;
  std::vector<cv::Mat> frames;  // grey
  std::vector<tracking::FrameTruth> truth;
};

// Every frame of the scene, or (quick) only the shots whose index is a multiple of `shotStride`
// (shots are 20 frames long in the sweep).
Recording record(const std::string& scene, cv::Size size, int shotStride) {
  Recording r;
  r.scene = scene;
  r.script = tracking::builtinScene(scene, ps::app::sourceDir());
  if (size != r.script.size) {
    r.script.size = size;
    r.script.camera = tracking::SynthScript::syntheticCamera(size);
  }
  const tracking::SynthRenderer renderer(r.script);
  app::Progress p("render " + scene + " " + std::to_string(size.width) + "x" +
                  std::to_string(size.height));
  for (int f = 0; f < renderer.frames(); ++f) {
    if ((f / 20) % shotStride != 0) continue;
    cv::Mat grey;
    cv::cvtColor(renderer.render(f), grey, cv::COLOR_BGR2GRAY);
    r.frames.push_back(grey);
    r.truth.push_back(renderer.truth(f));
    p.update(double(f + 1) / renderer.frames());
  }
  p.done(std::to_string(r.frames.size()) + " frames");
  return r;
}

struct Config {
  std::string label;
  tracking::DetectorConfig detector;
  bool filter = true;
};

// `bench track`'s options (`planetsculpt bench track --help`).
struct TrackSettings {
  std::string scene;     // sweep, tilt, near or board ("" = all)
  std::string detector;  // one configuration's label, on the sweep only ("" = all)
  // The single-marker rows' detector settings (defaults: DetectorConfig's).
  int searchEvery = tracking::DetectorConfig{}.searchEvery;
  double regionMargin = tracking::DetectorConfig{}.regionMargin;
  int minContrast = tracking::DetectorConfig{}.minContrast;
  // The single-marker rows' filters: translation, rotation and tip One Euro parameters (min
  // cutoff, beta, d cutoff each); empty: the SceneConfig defaults.
  std::vector<double> tune;
  BoardBenchSettings boards;
};

// The scene tracker's settings for the recording's two markers (with --tune's filters).
tracking::SceneConfig sceneConfig(const Recording& rec, const Config& c,
                                  const TrackSettings& settings, double touch) {
  tracking::SceneConfig sc;
  sc.planet.id = rec.script.planetId;
  sc.planet.size = rec.script.planetMarkerSize;
  sc.tool.id = rec.script.toolId;
  sc.tool.size = rec.script.toolMarkerSize;
  sc.planet.filter = sc.tool.filter = c.filter;
  sc.planetRadius = rec.script.planetRadius;
  sc.tipOffset = rec.script.tipOffset;
  sc.touchDistance = touch;
  if (settings.tune.size() == 9) {
    const auto& v = settings.tune;
    sc.planet.translation = sc.tool.translation = {v[0], v[1], v[2]};
    sc.planet.rotation = sc.tool.rotation = {v[3], v[4], v[5]};
    sc.tipFilter = {v[6], v[7], v[8]};
  }
  return sc;
}

// The configuration's detector for the scene's two ids, with the detector options' settings.
tracking::DetectorConfig detectorConfig(const Config& c, const tracking::SceneConfig& sc,
                                        const TrackSettings& settings) {
  tracking::DetectorConfig dc = c.detector;
  dc.ids = {sc.planet.id, sc.tool.id};
  dc.searchEvery = settings.searchEvery;
  dc.regionMargin = settings.regionMargin;
  dc.minContrast = settings.minContrast;
  return dc;
}

// A frame's measures (its `frame` filtered, `raw` unfiltered, against the truth), gathered over
// a recording for its row.
struct TrackTally {
  std::vector<double> cpuMs, ms, tipErr, tipRawErr, tipCamErr, rotErr;
  std::map<std::string, std::vector<double>> byDistance, byTilt;
  double maxToolTilt = 0;
  std::vector<std::pair<double, nlohmann::json>> worst;
  int flips = 0, rawFlips = 0, trackedBoth = 0, touchingFrames = 0, cvWithin = 0;
  int toolVisible = 0, toolFound = 0, planetVisible = 0, planetFound = 0;
  int drawnOff10 = 0;  // frames with a planet more than 10 mm off

  void addFrame(const tracking::SceneFrame& f, const tracking::SceneFrame& fr,
                const tracking::FrameTruth& gt, const core::LatLongChart& chart,
                double planetRadius, double touch) {
    drawnOff10 +=
        f.planetCentreValid && (f.planetCentreCamera - gt.planetCentreCamera).norm() > 0.01;
    toolVisible += gt.toolVisible;
    planetVisible += gt.planetVisible;
    toolFound += gt.toolVisible && f.tool.measured;
    planetFound += gt.planetVisible && f.planet.measured;
    if (!(gt.toolVisible && gt.planetVisible)) return;
    addFlips(f, fr, gt);
    if (!f.tipValid) return;
    ++trackedBoth;
    addTip(f, fr, gt);
    if (gt.tipHeight <= touch) {
      ++touchingFrames;
      const auto a = edit::nearestVertex(chart, f.tipPlanet);
      const auto b = edit::nearestVertex(chart, gt.tipPlanet);
      const double d =
          (chart.position(a.u, a.v, 0) - chart.position(b.u, b.v, 0)).norm() * planetRadius;
      cvWithin += d <= 0.003;
    }
  }

  // Poses more than 15 degrees off, filtered and raw.
  void addFlips(const tracking::SceneFrame& f, const tracking::SceneFrame& fr,
                const tracking::FrameTruth& gt) {
    if (f.planet.usable()) {
      const double e = tracking::rotationAngle(f.planet.pose.R, gt.planet.R) * 180 / M_PI;
      rotErr.push_back(e);
      flips += e > 15;
    }
    if (f.tool.usable()) {
      const double e = tracking::rotationAngle(f.tool.pose.R, gt.tool.R) * 180 / M_PI;
      rotErr.push_back(e);
      flips += e > 15;
    }
    if (fr.planet.measured)
      rawFlips += tracking::rotationAngle(fr.planet.pose.R, gt.planet.R) * 180 / M_PI > 15;
    if (fr.tool.measured)
      rawFlips += tracking::rotationAngle(fr.tool.pose.R, gt.tool.R) * 180 / M_PI > 15;
  }

  // The tip's error, binned by the camera's distance and the tool's tilt, and the worst frames.
  void addTip(const tracking::SceneFrame& f, const tracking::SceneFrame& fr,
              const tracking::FrameTruth& gt) {
    tipErr.push_back(1e3 * (f.tipPlanet - gt.tipPlanet).norm());
    worst.emplace_back(
        tipErr.back(),
        nlohmann::json{
            {"frame", gt.frame},
            {"tip_mm", tipErr.back()},
            {"planet_deg", tracking::rotationAngle(f.planet.pose.R, gt.planet.R) * 180 / M_PI},
            {"tool_deg", tracking::rotationAngle(f.tool.pose.R, gt.tool.R) * 180 / M_PI},
            {"planet_ratio", f.planet.ratio},
            {"tool_ratio", f.tool.ratio},
            {"planet_state", tracking::toString(f.planet.state)},
            {"tool_state", tracking::toString(f.tool.state)},
            {"planet_tilt", gt.planetTiltDeg},
            {"tool_tilt", gt.toolTiltDeg}});
    {
      char key[16];
      std::snprintf(key, sizeof key, "%.2f", std::round(gt.camera.t.norm() / 0.15) * 0.15);
      byDistance[key].push_back(tipErr.back());
    }
    {
      // The tool marker's tilt away from the line of sight, in 15-degree bins (0-15, 15-30, ...).
      char key[16];
      std::snprintf(key, sizeof key, "%02d-%02d", 15 * int(gt.toolTiltDeg / 15),
                    15 * int(gt.toolTiltDeg / 15) + 15);
      byTilt[key].push_back(tipErr.back());
      maxToolTilt = std::max(maxToolTilt, gt.toolTiltDeg);
    }
    tipCamErr.push_back(1e3 * (f.tipCamera - gt.tipCamera).norm());
    if (fr.tipValid) tipRawErr.push_back(1e3 * (fr.tipPlanet - gt.tipPlanet).norm());
  }
};

// The recording's row: times, detection rates, tip and rotation errors, flips, the five worst
// frames and the tip error by distance and tilt.
nlohmann::json trackRow(const Recording& rec, const Config& c, TrackTally& t) {
  nlohmann::json j = {
      {"bench", "track"},
      {"scene", rec.scene},
      {"detector", c.label},
      {"resolution",
       std::to_string(rec.script.size.width) + "x" + std::to_string(rec.script.size.height)},
      {"frames", rec.frames.size()},
      {"ms", round3(median(t.ms))},
      {"ms_p95", round3(percentile(t.ms, 0.95))},
      {"cpu_ms", round3(median(t.cpuMs))},
      {"cpu_ms_p95", round3(percentile(t.cpuMs, 0.95))},
      {"tool_detected", round3(t.toolVisible ? double(t.toolFound) / t.toolVisible : 0)},
      {"planet_detected", round3(t.planetVisible ? double(t.planetFound) / t.planetVisible : 0)},
      {"tip_frames", t.trackedBoth},
      {"tip_error_median_mm", round3(median(t.tipErr))},
      {"tip_error_p95_mm", round3(percentile(t.tipErr, 0.95))},
      {"tip_error_raw_median_mm", round3(median(t.tipRawErr))},
      {"tip_error_raw_p95_mm", round3(percentile(t.tipRawErr, 0.95))},
      {"tip_camera_error_median_mm", round3(median(t.tipCamErr))},
      {"rotation_error_median_deg", round3(median(t.rotErr))},
      {"flips", t.flips},
      {"raw_flips", t.rawFlips},
      {"touching_frames", t.touchingFrames},
      {"control_vertex_within_3mm",
       round3(t.touchingFrames ? double(t.cvWithin) / t.touchingFrames : 0)},
      {"tool_tilt_max_deg", round3(t.maxToolTilt)},
      {"drawn_off_10mm_frames", t.drawnOff10},
      {"drawn_off_10mm_fraction",
       round3(rec.frames.empty() ? 0 : double(t.drawnOff10) / rec.frames.size())},
      {"filtered", c.filter}};
  std::sort(t.worst.begin(), t.worst.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  for (std::size_t w = 0; w < std::min<std::size_t>(5, t.worst.size()); ++w)
    j["worst"].push_back(t.worst[w].second);
  for (const auto& [k, v] : t.byDistance)
    j["tip_error_by_distance_m"][k] = {
        {"median_mm", round3(median(v))}, {"p95_mm", round3(percentile(v, 0.95))}, {"n", v.size()}};
  for (const auto& [k, v] : t.byTilt)
    j["tip_error_by_tool_tilt_deg"][k] = {
        {"median_mm", round3(median(v))}, {"p95_mm", round3(percentile(v, 0.95))}, {"n", v.size()}};
  return j;
}

// Tracks the recording with the configuration (filtered, and unfiltered beside it), writes its
// row and returns the median time per frame (ms).
double evaluate(const Recording& rec, const Config& c, const TrackSettings& settings,
                const core::LatLongChart& chart, double touch, std::ostream& out) {
  const tracking::SceneConfig sc = sceneConfig(rec, c, settings, touch);
  const tracking::DetectorConfig dc = detectorConfig(c, sc, settings);
  auto detector = tracking::makeDetector(dc);
  auto rawDetector = tracking::makeDetector(dc);
  tracking::SceneTracker tracker(sc);
  tracking::SceneTracker rawTracker([&] {
    auto r = sc;
    r.planet.filter = r.tool.filter = false;
    return r;
  }());
  TrackTally t;
  const double dt = 1.0 / rec.script.fps;
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    const auto& gt = rec.truth[i];
    const double time = gt.frame * dt;
    if (i > 0 && ((gt.camera.inverse().t - rec.truth[i - 1].camera.inverse().t).norm() > 0.01 ||
                  tracking::rotationAngle(gt.camera.R, rec.truth[i - 1].camera.R) > 0.02)) {
      tracker.reset();  // a cut to another camera placement: a new shot
      rawTracker.reset();
    }
    tracking::SceneFrame f;
    const double cpu0 = threadCpuMs();
    const double ms = timeMs([&] {
      const auto d = detector->detect(rec.frames[i]);
      f = tracker.update(d, rec.script.camera, gt.frame, time);
    });
    t.cpuMs.push_back(threadCpuMs() - cpu0);
    t.ms.push_back(ms);
    const auto fr =
        rawTracker.update(rawDetector->detect(rec.frames[i]), rec.script.camera, gt.frame, time);
    t.addFrame(f, fr, gt, chart, rec.script.planetRadius, touch);
  }
  out << trackRow(rec, c, t).dump() << std::endl;
  return median(t.ms);
}

// The detector configurations of the single-marker rows; the first is the default.
std::vector<Config> detectorConfigs(bool quick) {
  std::vector<Config> configs;
  auto add = [&](const std::string& label, tracking::Backend b, double decimate, bool regions,
                 tracking::ArucoRefinement refine = tracking::ArucoRefinement::kContour) {
    Config c;
    c.label = label;
    c.detector.regions = regions;
    c.detector.backend = b;
    c.detector.decimate = decimate;
    c.detector.arucoRefinement = refine;
    configs.push_back(c);
  };
  add("apriltag d2 + regions", tracking::Backend::kAprilTag, 2.0, true);
  add("apriltag d2", tracking::Backend::kAprilTag, 2.0, false);
  add("apriltag d1", tracking::Backend::kAprilTag, 1.0, false);
  add("aruco contour + regions", tracking::Backend::kAruco, 1.0, true);
  if (!quick) {
    add("aruco contour", tracking::Backend::kAruco, 1.0, false);
    add("aruco apriltag-refine", tracking::Backend::kAruco, 1.0, false,
        tracking::ArucoRefinement::kAprilTag);
  }
  return configs;
}

void benchTrack(const BenchOptions& o, const TrackSettings& settings, std::ostream& out) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);  // "on one core": OpenCV's parallel loops off too
  const core::LatLongChart chart(core::GridSize::fromSide(2049), 1.0);
  const std::vector<Config> configs = detectorConfigs(o.quick);
  const int stride = o.quick ? 5 : 1;
  std::vector<cv::Size> sizes = {{640, 480}};
  if (!o.quick) sizes.push_back({1280, 720});
  // --scene runs one scene only (to re-measure one without the rest); board also runs the
  // single-marker default on the 640x480 sweep, its time baseline. --board-scene implies board.
  const std::string onlyScene =
      settings.scene.empty() && !settings.boards.scene.empty() ? "board" : settings.scene;
  auto wanted = [&](const std::string& scene) { return onlyScene.empty() || onlyScene == scene; };
  const bool baselineOnly = onlyScene == "board";
  if (baselineOnly) sizes = {{640, 480}};
  if (!wanted("sweep") && !baselineOnly) sizes.clear();
  const std::string& only = settings.detector;
  double defaultMs = 0;                    // the single-marker default on the 640x480 sweep
  std::optional<Recording> baselineSweep;  // kept to measure that default again
  for (const auto& size : sizes) {
    const Recording rec = record("sweep", size, stride);
    if (size.width == 640) baselineSweep = rec;
    for (const auto& c : configs)
      if ((only.empty() || c.label == only) && (!baselineOnly || &c == &configs[0])) {
        const double m = evaluate(rec, c, settings, chart, 0.004, out);
        if (size.width == 640 && &c == &configs[0]) defaultMs = m;
      }
    if (size.width == 640 && only.empty() && !baselineOnly) {
      Config raw = configs[0];
      raw.filter = false;
      raw.label += " unfiltered";
      evaluate(rec, raw, settings, chart, 0.004, out);
    }
  }
  // The tool marker turned up to 60 degrees away, 0.35-0.9 m; and the camera 0.30-0.33 m away,
  // where only some placements keep both markers in view: the default detector and aruco.
  if (only.empty()) {
    for (const char* scene : {"tilt", "near"}) {
      if (!wanted(scene)) continue;
      const Recording rec = record(scene, {640, 480}, stride);
      evaluate(rec, configs[0], settings, chart, 0.004, out);
      evaluate(rec, configs[3], settings, chart, 0.004, out);
    }
  }
  // The planet board and the tool cube (--scene board runs only these).
  if (only.empty() && wanted("board"))
    benchTrackBoards(
        o, settings.boards,
        [&] {
          if (!baselineSweep || defaultMs <= 0) return 0.0;
          std::ostream discard(nullptr);  // its row was written once, above
          return evaluate(*baselineSweep, configs[0], settings, chart, 0.004, discard);
        },
        out);
  cv::setNumThreads(threads);
}

void addTrackOptions(CLI::App& command, TrackSettings& s) {
  command.add_option("--scene", s.scene, "Only this scene (board: with its time baseline)")
      ->check(CLI::IsMember({"sweep", "tilt", "near", "board"}));
  command
      .add_option("--board-scene", s.boards.scene, "Only this board scene (implies --scene board)")
      ->check(CLI::IsMember(boardSceneNames()));
  std::vector<std::string> labels;
  for (const Config& c : detectorConfigs(false)) labels.push_back(c.label);
  command.add_option("--detector", s.detector, "Only this detector configuration, on the sweep")
      ->check(CLI::IsMember(labels));
  command
      .add_option("--search-every", s.searchEvery,
                  "Single-marker rows: whole-frame search at most every N frames")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command
      .add_option("--region-margin", s.regionMargin,
                  "Single-marker rows: search box margin, a fraction of the marker's size")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command
      .add_option("--min-contrast", s.minContrast,
                  "Single-marker rows: the detector's minimum contrast")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  command
      .add_option("--tune", s.tune,
                  "Single-marker rows: One Euro filters, translation, rotation, tip (min cutoff, "
                  "beta, d cutoff each)")
      ->delimiter(',')
      ->expected(9);
  command
      .add_option("--expected-search-every", s.boards.expectedSearchEvery,
                  "Board rows: whole-frame search every N frames while a covered board's markers "
                  "are expected (0: expectations ignored, as before)")
      ->check(CLI::Range(0, 1000));
  command
      .add_option("--expected-search-decimate", s.boards.expectedSearchDecimate,
                  "Board rows: AprilTag decimation of the whole-frame search while a covered "
                  "board is carried (0: off, the detector's own)")
      ->check(CLI::Range(0.0, 8.0));
  command
      .add_option("--dump", s.boards.dumpDir,
                  "Board scenes: one JSON line per frame in DIR/SCENE.jsonl")
      ->check(CLI::ExistingDirectory);
}

const BenchRegistration kTrack(
    "track", "Marker tracking against synthetic ground truth: single markers, board and cube",
    [](CLI::App& command) -> BenchFunction {
      auto s = std::make_shared<TrackSettings>();
      addTrackOptions(command, *s);
      return [s](const BenchOptions& o, std::ostream& out) { benchTrack(o, *s, out); };
    });

}  // namespace
}  // namespace ps::bench
