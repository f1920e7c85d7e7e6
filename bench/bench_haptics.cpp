// `planetsculpt bench haptics`: the 1 kHz haptic loop (src/haptics) on its own thread, timed
// while the editor thread does a live session's work on the default planet: every 33 ms it
// drains the loop's records, applies the presses (sand displacement through the edit pipeline),
// settles the sand (budgeted), publishes a terrain snapshot and tessellates a moving 1280x720
// view (the rendering stand-in, one OpenMP thread: "the other core").
//
// The device is scripted (ScriptedDevice): the demo's kind of stroke on a 6 cm globe, repeated
// every 3 s: down to 1.5 mm below the surface, dragged 8 degrees east, lifted. The default planet
// on lat-long and on the octahedral chart (each row names its `chart`): first the tick's work on
// both, offline and in turn (tickCompare), then per chart two runs: the loop alone (no editor
// work) and the loop beside the editor. Per run one JSON line: the loop's rate,
// wake-up period (median, p99, max), per-tick compute time (read + depth + force + queue:
// median, p99, max), deadlines missed, whether SCHED_FIFO was granted, the editor's frame times,
// and the machine's load average before and after (the machine is shared: read the figures with
// the load next to them).
#include <omp.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <thread>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/build_paths.hpp"
#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/demo_options.hpp"
#include "core/chart_factory.hpp"
#include "edit/edit_pipeline.hpp"
#include "haptics/device.hpp"
#include "haptics/force_path.hpp"
#include "haptics/haptic_core.hpp"
#include "haptics/terrain_patch.hpp"
#include "replay/replay.hpp"
#include "sand/settler.hpp"
#include "terrain/camera.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/calibration.hpp"
#include "tracking/video.hpp"

namespace ps::bench {

namespace {

constexpr double kGlobe = 0.06;  // m: the displayed planet's radius (tracking's default)

std::array<double, 3> loadAverageValues() {
  std::array<double, 3> l{-1, -1, -1};
  std::ifstream f("/proc/loadavg");
  f >> l[0] >> l[1] >> l[2];
  return l;
}

Eigen::Vector3d dirAt(double latDeg, double lonDeg) {
  const double la = latDeg * std::numbers::pi / 180, lo = lonDeg * std::numbers::pi / 180;
  return {std::cos(lo) * std::cos(la), std::sin(lo) * std::cos(la), std::sin(la)};
}

// The stroke in the device frame (m from the globe's centre), period 3 s: along the parallel
// `lat` from longitude lonA to lonB (degrees).
haptics::ScriptedDevice::Path strokePath(const terrain::Terrain& planet, double scale,
                                         double lat = 30, double lonA = 20, double lonB = 28) {
  const core::Chart& chart = planet.chart();
  auto surfaceAt = [&](const Eigen::Vector3d& d) {
    const auto uv = chart.inverse(d);
    return (chart.sphereRadius() +
            planet.height(int(std::lround((*uv)(0))), int(std::lround((*uv)(1))))) /
           scale;
  };
  const Eigen::Vector3d a = dirAt(lat, lonA), b = dirAt(lat, lonB);
  const double ra = surfaceAt(a), rb = surfaceAt(b);
  auto key = haptics::ScriptedDevice::keyframes({{0.0, a * (ra + 0.003)},
                                                 {0.8, a * (ra - 0.0015)},
                                                 {1.8, b * (rb - 0.0015)},
                                                 {2.4, b * (rb + 0.003)},
                                                 {3.0, a * (ra + 0.003)}});
  return [key](double t) { return key(std::fmod(t, 3.0)); };
}

void run(bool withEditor, const BenchOptions& options, terrain::Terrain& planet,
         std::ostream& out) {
  const double seconds = options.quick ? 2.0 : 8.0;
  const double R = planet.chart().sphereRadius();
  edit::EditPipeline pipe(planet);
  pipe.setUndoEnabled(false);
  sand::Settler settler(planet, sand::Material::sand(), {.cellBudget = std::size_t(1) << 18});
  haptics::ForcePathConfig cfg;
  cfg.map.scale = R / kGlobe;
  cfg.press.displacement.radius = 60e3;
  haptics::ForcePath session(planet, withEditor ? &pipe : nullptr, cfg,
                             withEditor ? &settler : nullptr);
  std::ostringstream forceLog;
  if (withEditor) session.setLog(&forceLog);
  haptics::ScriptedDevice device(strokePath(planet, cfg.map.scale), "scripted-stroke");
  session.focus(dirAt(30, 20) * R);
  haptics::LoopOptions lo;
  lo.timingCapacity = std::size_t(seconds * cfg.haptics.rateHz * 1.5) + 1000;
  const auto load0 = loadAverageValues();
  const int savedThreads = omp_get_max_threads();
  omp_set_num_threads(1);
  terrain::Tessellator tess;
  std::vector<double> frameMs;
  std::size_t triangles = 0;
  int stamps = 0;
  session.startLoop(device, lo);
  const auto t0 = std::chrono::steady_clock::now();
  auto next = t0;
  int frame = 0;
  while (std::chrono::steady_clock::now() - t0 < std::chrono::duration<double>(seconds)) {
    next += std::chrono::microseconds(33333);
    std::this_thread::sleep_until(next);
    if (!withEditor) continue;
    const double ms = timeMs([&] {
      const haptics::FrameForces f = session.editorFrame();
      stamps += f.stamps;
      settler.frame();
      const double a = 0.02 * frame++;
      const Eigen::Vector3d target = dirAt(30, 24) * R;
      const Eigen::Vector3d eye = target +
                                  0.12 * R * (dirAt(30 + 10 * std::sin(a), 24 + 10 * std::cos(a))) +
                                  0.05 * R * target.normalized();
      const terrain::Camera cam = terrain::Camera::lookAt(eye, target, target.normalized(), 1280,
                                                          720, 60 * std::numbers::pi / 180);
      triangles = tess.tessellate(planet, cam, {}).triangleCount();
    });
    frameMs.push_back(ms);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const haptics::LoopStats st = session.loop()->stats();
  const std::vector<haptics::TickTiming> tt = session.loop()->timings();
  if (withEditor) session.editorFrame();
  session.stopLoop();
  omp_set_num_threads(savedThreads);
  const auto load1 = loadAverageValues();

  std::vector<double> period, compute;
  for (const haptics::TickTiming& x : tt) {
    period.push_back(x.periodUs * 1e-3);
    compute.push_back(x.computeUs);
  }
  std::uint64_t faults = 0;
  nlohmann::json byFault = nlohmann::json::object();
  for (std::size_t i = 1; i < st.faults.size(); ++i) {
    faults += st.faults[i];
    if (st.faults[i]) byFault[haptics::toString(haptics::Fault(i))] = st.faults[i];
  }
  if (!options.outDir.empty() && withEditor) {
    std::ofstream(options.outDir + "/haptics_forces.csv") << forceLog.str();
  }
  nlohmann::json j = {
      {"bench", "haptics"},
      {"run", withEditor ? "loop+editor" : "loop-alone"},
      {"chart", planet.chart().name()},
      {"grid", planet.grid().label()},
      {"seconds", wall},
      {"target_rate_hz", cfg.haptics.rateHz},
      {"rate_hz", double(st.ticks) / wall},
      {"ticks", st.ticks},
      {"period_median_ms", median(period)},
      {"period_p99_ms", percentile(period, 0.99)},
      {"period_p999_ms", percentile(period, 0.999)},
      {"period_max_ms", period.empty() ? 0.0 : *std::max_element(period.begin(), period.end())},
      {"tick_us_median", median(compute)},
      {"tick_us_p99", percentile(compute, 0.99)},
      {"tick_us_max", st.maxComputeUs},
      {"missed_deadlines", st.missedDeadlines},
      {"dropped_records", st.droppedRecords},
      {"faults", faults},
      {"faults_by_kind", byFault},
      {"realtime_priority", st.realtimePriority},
      {"editor_frames", frameMs.size()},
      {"editor_frame_ms_median", median(frameMs)},
      {"editor_frame_ms_max",
       frameMs.empty() ? 0.0 : *std::max_element(frameMs.begin(), frameMs.end())},
      {"editor_triangles", triangles},
      {"stamps", stamps},
      {"load_avg_before", load0},
      {"load_avg_after", load1},
      {"cpus", std::thread::hardware_concurrency()},
      {"note",
       "shared machine: compare with the load average; targets tick_us <= 20, p99 period <= "
       "1.5 ms"}};
  out << j.dump() << "\n" << std::flush;
  std::cerr << "haptics " << (withEditor ? "loop+editor" : "loop-alone") << " "
            << planet.chart().name() << ": " << double(st.ticks) / wall << " Hz, period median "
            << median(period) << " ms p99 " << percentile(period, 0.99) << " ms max "
            << j["period_max_ms"].get<double>() << " ms, tick median " << median(compute)
            << " us p99 " << percentile(compute, 0.99) << " us, load " << load1[0] << "\n";
}

// The haptic tick on the sphere's charts (issue 43): the loop's work per tick (the scripted
// device read, the depth in the patch, the force law and clamps: HapticCore::tick) timed
// offline, without the loop's sleeps, on the same stroke on each planet; the patch captured
// about the tip every 33 ticks as the editor does every frame (not timed). Each repetition runs
// one 3 s stroke (3,000 ticks) per chart, the charts in turn, the order rotated; a row per
// chart and scene with the median per-tick time and the median over the repetitions of its
// time over lat-long's in the same repetition. Scenes: the live run's stroke (30 N, 20 -> 28 E)
// and one across the octahedral chart's fold at 0 E (30 S, 4 W -> 4 E), where its patch holds
// the box's images across the fold.
void tickCompare(const BenchOptions& options, const std::vector<const terrain::Terrain*>& planets,
                 std::ostream& out) {
  struct Scene {
    const char* name;
    double lat, lonA, lonB;
  };
  const int repeats = options.quick ? 5 : 9;
  for (const Scene& scene : {Scene{"mid-latitude", 30, 20, 28}, Scene{"fold", -30, -4, 4}}) {
    struct Run {
      const terrain::Terrain* planet;
      haptics::ForcePathConfig cfg;
      int halfSize = 0;
      std::vector<double> usPerTick;
      std::uint64_t touching = 0, images = 0;
    };
    std::vector<Run> runs;
    for (const terrain::Terrain* planet : planets) {
      Run r;
      r.planet = planet;
      r.cfg.map.scale = planet->chart().sphereRadius() / kGlobe;
      r.cfg.press.displacement.radius = 60e3;
      r.halfSize = haptics::ForcePath(*planet, nullptr, r.cfg).patchHalfSize();
      runs.push_back(std::move(r));
    }
    for (int k = 0; k < repeats; ++k) {
      for (std::size_t j = 0; j < runs.size(); ++j) {
        Run& r = runs[(j + std::size_t(k)) % runs.size()];
        haptics::ScriptedDevice device(
            strokePath(*r.planet, r.cfg.map.scale, scene.lat, scene.lonA, scene.lonB));
        haptics::HapticCore core(r.cfg.haptics, r.cfg.map);
        haptics::TerrainPatch patch;
        const int ticks = 3000;
        double us = 0;
        Eigen::Vector3d pos = Eigen::Vector3d::Zero();
        for (int i = 0; i < ticks; i += 33) {
          if (device.read(i * 1e-3, pos) &&
              !patch.capture(*r.planet, r.cfg.map.toPlanet(pos), r.halfSize))
            patch.clear();
          r.images += std::uint64_t(patch.images());
          const auto t0 = std::chrono::steady_clock::now();
          for (int q = i; q < std::min(ticks, i + 33); ++q) {
            const double t = q * 1e-3;
            const bool ok = device.read(t, pos);
            const haptics::ForceRecord rec =
                core.tick(t, ok, pos, patch.valid() ? &patch : nullptr);
            r.touching += rec.force.squaredNorm() > 0 ? 1 : 0;
          }
          us += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                    .count();
        }
        r.usPerTick.push_back(us / ticks);
      }
    }
    for (const Run& r : runs) {
      std::vector<double> ratios;
      for (int k = 0; k < repeats; ++k)
        ratios.push_back(r.usPerTick[std::size_t(k)] / runs[0].usPerTick[std::size_t(k)]);
      nlohmann::json j = {
          {"bench", "haptics"},
          {"run", "tick-compare"},
          {"scene", scene.name},
          {"chart", r.planet->chart().name()},
          {"grid", r.planet->grid().label()},
          {"repetitions", repeats},
          {"ticks_per_repetition", 3000},
          {"touching_ticks", r.touching / std::uint64_t(repeats)},
          {"patch_images", r.images},
          {"tick_us_median", median(r.usPerTick)},
          {"tick_time_ratio_vs_latlong", median(ratios)},
          {"tick_time_ratio_vs_latlong_min", *std::min_element(ratios.begin(), ratios.end())},
          {"tick_time_ratio_vs_latlong_max", *std::max_element(ratios.begin(), ratios.end())},
          {"load_avg", loadAverageValues()},
          {"note", "offline ticks (no sleeps), charts in turn; shared machine"}};
      out << j.dump() << "\n" << std::flush;
      std::cerr << "haptics tick " << scene.name << " " << r.planet->chart().name() << ": "
                << median(r.usPerTick) << " us a tick, x" << median(ratios)
                << " lat-long's (median of the repetitions), " << r.touching / repeats
                << " touching ticks\n";
    }
  }
}

// Force magnitude, repulse and depth against time, as a PNG (OpenCV drawing; no plotting
// library in the dependencies).
void plotForces(const std::vector<haptics::ForceRecord>& rs, const std::string& path,
                const std::string& title) {
  if (rs.empty()) return;
  const int W = 1200, H = 420, L = 70, Rm = 20, T = 40, B = 50;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  const double t0 = rs.front().time, t1 = std::max(rs.back().time, t0 + 1e-3);
  double fmax = 1.0;
  for (const auto& r : rs) fmax = std::max(fmax, r.force.norm());
  fmax = std::ceil(fmax);
  auto X = [&](double t) { return int(L + (W - L - Rm) * (t - t0) / (t1 - t0)); };
  auto Y = [&](double f) { return int(H - B - (H - B - T) * f / fmax); };
  const cv::Scalar grid(220, 220, 220), axis(0, 0, 0);
  for (int k = 0; k <= int(fmax); ++k) {
    cv::line(img, {L, Y(k)}, {W - Rm, Y(k)}, grid);
    cv::putText(img, std::to_string(k), {L - 25, Y(k) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, axis);
  }
  const double step = (t1 - t0) > 20 ? 5.0 : 1.0;
  for (double t = std::ceil(t0 / step) * step; t <= t1; t += step) {
    cv::line(img, {X(t), T}, {X(t), H - B}, grid);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", t);
    cv::putText(img, buf, {X(t) - 8, H - B + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, axis);
  }
  for (std::size_t i = 1; i < rs.size(); ++i) {
    const auto& a = rs[i - 1];
    const auto& b = rs[i];
    if (b.fault != haptics::Fault::kNone)
      cv::line(img, {X(b.time), H - B}, {X(b.time), H - B + 4}, cv::Scalar(0, 0, 255));
    cv::line(img, {X(a.time), Y(a.force.norm())}, {X(b.time), Y(b.force.norm())},
             cv::Scalar(180, 60, 0), 1, cv::LINE_AA);
  }
  cv::rectangle(img, {L, T}, {W - Rm, H - B}, axis);
  cv::putText(img, title, {L, T - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.55, axis, 1, cv::LINE_AA);
  cv::putText(img, "|F| (N)", {5, T - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.45, axis);
  cv::putText(img, "time (s); red ticks: zero force by a fault (tool not tracked)", {L, H - 10},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, axis);
  cv::imwrite(path, img);
}

// The bundled demo video replayed (replay::runReplay, brush tool as in `planetsculpt demo`) with
// the force path hooked in through replay's frame hook: forces only, offline ticks at 1 kHz
// between frames, the force log kept. Reports the per-frame cost of onFrame.
void demoReplay(const BenchOptions& options, std::ostream& out) {
  const std::string video = (ps::app::sourceDir() / "data/demo.mkv").string();
  const std::string calibPath = (ps::app::sourceDir() / "calib/synthetic-640x480.yml").string();
  if (!std::ifstream(video)) {
    std::cerr << "haptics demo-replay: " << video << " missing, skipped\n";
    return;
  }
  tracking::FrameSource source(video);
  const auto calib = tracking::loadCalibration(calibPath);
  auto planet = app::makeDefaultPlanet(options.quick ? 9 : 11, 1, core::ChartShape::kLatLong);
  replay::ReplayOptions ro = demoReplayOptions();
  if (options.quick) ro.maxFrames = 150;
  haptics::ForcePathConfig cfg;
  cfg.map.scale = planet->chart().sphereRadius() / ro.scene.planetRadius;
  haptics::ForcePath session(*planet, nullptr, cfg);
  std::ostringstream csv;
  session.setLog(&csv);
  std::vector<double> frameMs;
  int frames = 0, touchingTicks = 0;
  double maxF = 0;
  std::ostringstream log;
  replay::runReplay(source, calib, *planet, ro, log, nullptr, {},
                    [&](const replay::FrameContext& c) {
                      std::optional<Eigen::Vector3d> tip;
                      if (c.scene.tipValid) tip = c.scene.tipPlanet * c.scale;
                      haptics::FrameForces f;
                      frameMs.push_back(timeMs([&] { f = session.onFrame(tip, c.time); }));
                      ++frames;
                      touchingTicks += f.touchingTicks;
                      maxF = std::max(maxF, f.maxForce);
                    });
  std::istringstream in(csv.str());
  const auto rs = haptics::readForceLog(in);
  if (!options.outDir.empty()) {
    std::ofstream(options.outDir + "/haptics_demo_forces.csv") << csv.str();
    plotForces(rs, options.outDir + "/haptics_demo_forces.png",
               "planetsculpt demo replay: force on the tool tip (paper 004 sand, 1 kHz)");
  }
  nlohmann::json j = {{"bench", "haptics"},
                      {"run", "demo-replay"},
                      {"grid", planet->grid().label()},
                      {"frames", frames},
                      {"ticks", rs.size()},
                      {"touching_ticks", touchingTicks},
                      {"max_force_n", maxF},
                      {"on_frame_ms_median", median(frameMs)},
                      {"on_frame_ms_max",
                       frameMs.empty() ? 0.0 : *std::max_element(frameMs.begin(), frameMs.end())},
                      {"load_avg", loadAverageValues()}};
  out << j.dump() << "\n" << std::flush;
  std::cerr << "haptics demo-replay: " << frames << " frames, " << rs.size() << " ticks, "
            << touchingTicks << " touching, max " << maxF << " N, onFrame median "
            << median(frameMs) << " ms\n";
}

}  // namespace

void benchHaptics(const BenchOptions& options, std::ostream& out) {
  const int level = options.quick ? 10 : 12;
  auto planet = app::makeDefaultPlanet(level, 1, core::ChartShape::kLatLong);
  auto octahedral = app::makeDefaultPlanet(level, 1, core::ChartShape::kOctahedral);
  tickCompare(options, {planet.get(), octahedral.get()}, out);
  for (terrain::Terrain* p : {planet.get(), octahedral.get()}) {
    run(false, options, *p, out);
    run(true, options, *p, out);
  }
  demoReplay(options, out);
}

static const BenchRegistration kHaptics("haptics",
                                        "The 1 kHz haptic loop beside the editor thread's work",
                                        benchHaptics);

}  // namespace ps::bench
