// `planetsculpt bench live`: the frame loop's time with the session's saving on and off
// (issue 42 part 4, docs/LIVE.md "The writer thread"). A scripted session on the default planet:
// a brush stroke of 1 s every --stroke-every s (default 3) of session time, one stamp per
// frame at 30 fps of session time, the AR view's tessellation (640x480, dist_max 4 px, a camera
// circling the planet at 3 radii, as the live app's drawView), and with saving on the live app's
// SessionStore (the journal fed by the undo journal's listener, tick() once a frame, an autosave
// every --autosave s, default 10). With --pace realtime (the default) the frames keep the live
// app's 30 fps of wall time, so a 300 s session takes 5 minutes and the writer has the time
// between frames a live session gives it; --pace fast runs the frames back to back (session
// time advances 1/30 s a frame), so the saves come back to back: a harder case than the live
// app's, a stress test of the writer rather than the live loop's figure. Each frame's
// time is its edit and tessellation work plus, with saving on, the store's work on the frame
// thread. Rows per planet side (--sides, default 4097,8193; --quick: 1025) and
// --seconds of session (default 300; --quick: 30), run off, on and off again: p50, p99
// and max frame time, the ratios of on to the mean of the two off runs, the saves, records and the
// writer's times. The writer thread competes with the frame loop for the machine's cores (nproc and
// the load go with the rows).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>
#include <thread>

#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "core/chart_factory.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "session/session_store.hpp"
#include "terrain/tessellator.hpp"

namespace ps::bench {

namespace {

struct LiveRun {
  std::vector<double> frameMs;
  int strokes = 0;
  session::SessionWriterStats writer;
  std::uint64_t savesStarted = 0;
  double copyMaxMs = 0;
};

// One scripted session on `planet`; saving into `outDir` when it is not empty.
LiveRun runSession(terrain::Terrain& planet, double seconds, double autosave, double strokeEvery,
                   bool realtime, const std::filesystem::path& outDir) {
  constexpr double kFps = 30;
  edit::EditPipeline pipe(planet);
  edit::GaussianBrush brush;
  edit::BrushSettings s;
  s.radius = 500e3;
  s.sigma = 0.3;
  s.strength = 400;
  brush.setSettings(s);
  std::unique_ptr<session::SessionStore> store;
  if (!outDir.empty()) {
    std::filesystem::create_directories(outDir);
    store =
        std::make_unique<session::SessionStore>(planet, session::SessionFiles::in(outDir),
                                                session::SessionStoreOptions{autosave, true}, 0.0);
    pipe.journal().setListener(store.get());
  }
  std::mt19937 rng(7);
  terrain::Tessellator tessellator;
  const terrain::TessellationSettings view;
  const double R = planet.chart().sphereRadius();
  LiveRun run;
  const int frames = int(seconds * kFps);
  Eigen::Vector3d at = Eigen::Vector3d::UnitX() * R, step = Eigen::Vector3d::Zero();
  run.frameMs.reserve(std::size_t(frames));
  const auto start = std::chrono::steady_clock::now();
  for (int f = 0; f < frames; ++f) {
    // A frame late (its work overran 1/30 s) starts at once, as the live loop's would.
    if (realtime)
      std::this_thread::sleep_until(start +
                                    std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        std::chrono::duration<double>(f / kFps)));
    const double now = f / kFps;
    const double phase = std::fmod(now, strokeEvery);
    const auto t0 = std::chrono::steady_clock::now();
    if (phase < 1.0) {
      if (!pipe.inStroke()) {
        std::uniform_real_distribution<double> u(-1, 1);
        at = Eigen::Vector3d(u(rng), u(rng), 0.6 * u(rng)).normalized() * R;
        step = Eigen::Vector3d(u(rng), u(rng), u(rng)) * (0.004 * R);
        pipe.beginStroke(brush, {at, 0});
        ++run.strokes;
      } else {
        at = (at + step).normalized() * R;
        pipe.moveTo({at, 1.0 / kFps});
      }
    } else if (pipe.inStroke()) {
      pipe.endStroke();
    }
    const double a = 0.02 * f;
    const Eigen::Vector3d eye = 3 * R * Eigen::Vector3d(std::cos(a), std::sin(a), 0.3).normalized();
    tessellator.tessellate(planet,
                           terrain::Camera::lookAt(eye, Eigen::Vector3d::Zero(),
                                                   Eigen::Vector3d::UnitZ(), 640, 480, 1.0),
                           view);
    if (store) store->tick(now, pipe.inStroke());
    run.frameMs.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  if (pipe.inStroke()) pipe.endStroke();
  if (store) {
    store->flush();
    run.writer = store->writerStats();
    run.savesStarted = store->saves();
    run.copyMaxMs = store->copyMaxMs();
    pipe.journal().setListener(nullptr);
  }
  return run;
}

}  // namespace

// `bench live`'s options; 0 / empty: the defaults (below).
struct LiveSettings {
  std::vector<int> sides;  // planet sides, each 2^n + 1
  double seconds = 0;      // of session per run
  double autosave = 10;    // s between autosaves
  double strokeEvery = 3;  // s of session between strokes
  std::string pace;  // realtime: 30 fps of wall time; fast: frames back to back ("": by --quick)
};

void benchLive(const BenchOptions& options, const LiveSettings& settings, std::ostream& out) {
  const double seconds = settings.seconds > 0 ? settings.seconds : options.quick ? 30 : 300;
  const double autosave = settings.autosave, strokeEvery = settings.strokeEvery;
  // The CI's --quick run checks the rows, not the timing: back to back.
  const std::string pace = !settings.pace.empty() ? settings.pace
                           : options.quick        ? "fast"
                                                  : "realtime";
  const bool realtime = pace == "realtime";
  std::vector<int> sides = settings.sides;
  if (sides.empty()) sides = options.quick ? std::vector<int>{1025} : std::vector<int>{4097, 8193};
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("ps_bench_live_" + std::to_string(::getpid()));
  for (const int side : sides) {
    const std::string item = std::to_string(side);
    int level = 0;
    while ((1 << level) + 1 < side) ++level;
    std::cerr << "bench live: " << side << "² planet ...\n";
    auto planet = app::makeDefaultPlanet(level, 1);
    const std::string loadBefore = loadAverage();
    std::cerr << "bench live: " << seconds << " s of session, saving off\n";
    const LiveRun off = runSession(*planet, seconds, autosave, strokeEvery, realtime, {});
    std::cerr << "bench live: the same, saving on (autosave every " << autosave << " s)\n";
    const LiveRun on = runSession(*planet, seconds, autosave, strokeEvery, realtime, dir / item);
    std::filesystem::remove_all(dir / item);
    // The machine's load drifts: saving on is compared with the mean of the runs before and
    // after it.
    std::cerr << "bench live: the same, saving off again\n";
    const LiveRun off2 = runSession(*planet, seconds, autosave, strokeEvery, realtime, {});
    const double p99Off = 0.5 * (percentile(off.frameMs, 0.99) + percentile(off2.frameMs, 0.99));
    const double maxOff = 0.5 * (percentile(off.frameMs, 1.0) + percentile(off2.frameMs, 1.0));
    const double p99On = percentile(on.frameMs, 0.99), maxOn = percentile(on.frameMs, 1.0);
    int order = 0;
    for (const auto* r : {&off, &on, &off2}) {
      const bool saving = r == &on;
      nlohmann::json row{
          {"bench", "live"},
          {"side", side},
          {"run", ++order},
          {"saving", saving},
          {"session_s", seconds},
          {"pace", pace},
          {"chart", core::toString(app::kDefaultChart)},
          {"frames", r->frameMs.size()},
          {"strokes", r->strokes},
          {"frame_p50_ms", round3(median(r->frameMs))},
          {"frame_p99_ms", round3(percentile(r->frameMs, 0.99))},
          {"frame_max_ms", round3(percentile(r->frameMs, 1.0))},
          {"frame_mean_ms", round3(std::accumulate(r->frameMs.begin(), r->frameMs.end(), 0.0) /
                                   double(r->frameMs.size()))}};
      if (saving) {
        row["autosave_s"] = autosave;
        row["saves_started"] = r->savesStarted;
        row["saves_done"] = r->writer.savesDone;
        row["save_max_ms"] = round3(r->writer.saveMaxMs);
        row["records"] = r->writer.records;
        row["record_write_max_ms"] = round3(r->writer.recordMaxMs);
        row["record_on_disk_after_max_ms"] = round3(r->writer.recordLagMaxMs);
        row["frame_copy_max_ms"] = round3(r->copyMaxMs);
      }
      out << row.dump() << std::endl;
    }
    out << nlohmann::json{{"bench", "live"},
                          {"side", side},
                          {"case", "saving_on_vs_off"},
                          {"pace", pace},
                          {"p99_ratio", round3(p99On / p99Off)},
                          {"max_ratio", round3(maxOn / maxOff)},
                          {"p99_target", 1.2},
                          {"max_target", 2.0},
                          {"nproc", std::thread::hardware_concurrency()},
                          {"load_before", loadBefore},
                          {"load_after", loadAverage()}}
               .dump()
        << std::endl;
  }
  std::filesystem::remove_all(dir);
}

// A side the planet's grid can have: 2^n + 1, 3 .. 16385.
std::string notAGridSide(const std::string& text) {
  int side = 0;
  try {
    std::size_t used = 0;
    side = std::stoi(text, &used);
    if (used != text.size()) side = 0;
  } catch (const std::exception&) {
  }
  for (int level = 1; level <= 14; ++level)
    if ((1 << level) + 1 == side) return "";
  return "side " + text + " is not 2^n + 1 (3 .. 16385)";
}

static const BenchRegistration kLive(
    "live", "The live frame loop with the session's saving on and off",
    [](CLI::App& command) -> BenchFunction {
      auto s = std::make_shared<LiveSettings>();
      command
          .add_option("--sides", s->sides,
                      "Planet sides, comma-separated (default 4097,8193; --quick: 1025)")
          ->delimiter(',')
          ->check(CLI::Validator(notAGridSide, "2^n+1"));
      command
          .add_option("--seconds", s->seconds, "Session time per run (default 300; --quick: 30)")
          ->check(CLI::PositiveNumber);
      command.add_option("--autosave", s->autosave, "Seconds between autosaves")
          ->capture_default_str()
          ->check(CLI::PositiveNumber);
      command.add_option("--stroke-every", s->strokeEvery, "Seconds of session between strokes")
          ->capture_default_str()
          ->check(CLI::PositiveNumber);
      command
          .add_option(
              "--pace", s->pace,
              "realtime: frames at 30 fps of wall time, as the live app (a 300 s session "
              "takes 5 min; the default); fast: frames back to back, saves back to back (a stress "
              "test; the default with --quick)")
          ->check(CLI::IsMember({"realtime", "fast"}));
      return [s](const BenchOptions& o, std::ostream& out) { benchLive(o, *s, out); };
    });

}  // namespace ps::bench
