// `planetsculpt bench erosion`: throughput of the sand core (src/sand) and the frames a standard
// crater needs to settle under a per-frame budget.
//
// Throughput: a 2049^2 window (a flat chart, 1 m cells; --quick: 513^2) of uniform noise +-10 m,
// steep everywhere, so that every step visits every cell; the state is loaded and warmed up, then
// `repeats` steps are timed one by one. One JSON line per method and thread count (1 and 2, set
// with omp_set_num_threads): cell_steps_per_s from the median step, volume_drift = |V_after -
// V_before| / sum A |h| over all steps run; cell_steps_per_cpu_s divides by the process's CPU
// time instead (all threads): on a shared machine it shows what the code does per core while the
// wall-clock figure shows how much of the machine it got (cpu_utilisation). Methods: thermal
// erosion (sand, talus 30 deg, c = 1), explicit drift-diffusion at its stability bound (sand, D =
// 1: dt = 0.25), semi-implicit drift-diffusion at dt = 1 (4x the explicit bound).
//
// Crater: sand 20 m deep on a 1025^2 flat grid of 1 m cells (--quick: 257^2), the displacement
// tool (r = 16 m) pressed 12 m deep at the centre through the edit pipeline, then settled by the
// Settler frame by frame with a budget of 2^20 cell-steps per frame (whole steps, at most 256
// per frame: the Settler's defaults); and the same
// crater scaled to the default planet (2049^2 lat-long, 6,372.79 km; r = 200 km, 80 km deep, at
// 45 degrees north; --quick: 513^2).
// Reports frames, steps and cell-steps to rest, per-frame milliseconds (median and max; bounds
// update included) and the volume drift of the float heights.
//
// Sphere throughput (issue 28): the same on a planet of radius m / pi m (lat-long's meridian
// spacing 1 m) at 1025^2 (--quick: 257^2), on lat-long and on the octahedral chart in the same
// run (`chart`), and on a torus and a cylinder of 1 m steps round the tube, noise +-10 m per
// distinct point; thermal, explicit diffusion at each chart's bound and semi-implicit diffusion at
// 4x it (on the glued charts along lines continued across the folds and seams). The four charts
// are stepped in turn and each row carries the median over the repetitions of its rate over
// lat-long's in the same repetition (`rate_ratio_vs_latlong`; `cpu_rate_ratio_vs_latlong` the same
// per CPU-second of the process, which a loaded machine's scheduling disturbs less on one
// thread); `bench erosion-charts` runs these
// rows alone. The planet crater runs on both sphere charts too.
//
// The machine this was written on is shared with other builds: timings are noisy; compare runs
// taken back to back.
#include <omp.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/sand_field.hpp"
#include "sand/settler.hpp"
#include "terrain/terrain.hpp"

namespace ps::bench {

namespace {

enum class Method { kThermal, kExplicit, kSemiImplicit };

// CPU time of the whole process (all threads), seconds.
double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

const char* methodName(Method m) {
  switch (m) {
    case Method::kThermal:
      return "thermal";
    case Method::kExplicit:
      return "diffusion-explicit";
    case Method::kSemiImplicit:
      return "diffusion-implicit";
  }
  return "?";
}

void throughput(int n, Method method, int threads, int repeats, std::ostream& out) {
  auto chart = std::make_shared<core::FlatChart>(core::GridSize(n), 1.0, 1.0);
  const core::GridSize g = chart->grid();
  std::vector<float> h(g.count());
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> noise(-10.0f, 10.0f);
  for (float& x : h) x = 100.0f + noise(rng);
  const sand::SandGrid grid(chart);
  const double scale = grid.absVolume(h);
  sand::SandField field(chart, h);
  const sand::Material mat = sand::Material::sand();
  omp_set_num_threads(threads);
  field.markAll();
  auto step = [&] {
    switch (method) {
      case Method::kThermal:
        return field.thermalStep(mat);
      case Method::kExplicit:
        return field.diffusionStep(mat, 0.25, sand::DiffusionScheme::kExplicit,
                                   sand::StepPolicy::kRefuse);
      case Method::kSemiImplicit:
        return field.diffusionStep(mat, 1.0, sand::DiffusionScheme::kSemiImplicit);
    }
    return sand::StepReport{};
  };
  step();  // loads every tile
  const double v0 = field.volume();
  std::vector<double> rates, cpuRates;
  std::size_t cells = 0;
  double totalMs = 0, totalCpu = 0;
  for (int k = 0; k < repeats; ++k) {
    sand::StepReport r;
    const double c0 = cpuSeconds();
    const double t = timeMs([&] { r = step(); });
    const double cpu = cpuSeconds() - c0;
    rates.push_back(double(r.cells) / (t * 1e-3));
    cpuRates.push_back(double(r.cells) / std::max(cpu, 1e-9));
    cells += r.cells;
    totalMs += t;
    totalCpu += cpu;
  }
  const double drift = std::abs(field.volume() - v0) / scale;
  nlohmann::json j = {{"bench", "erosion"},
                      {"method", methodName(method)},
                      {"chart", "flat"},
                      {"grid", g.label()},
                      {"threads", threads},
                      {"steps", repeats},
                      {"cells_per_step", cells / std::size_t(std::max(1, repeats))},
                      {"cell_steps_per_s", median(rates)},
                      {"cell_steps_per_s_best", *std::max_element(rates.begin(), rates.end())},
                      {"ms_per_step", totalMs / repeats},
                      {"cell_steps_per_cpu_s", median(cpuRates)},
                      {"cpu_utilisation", totalCpu / (totalMs * 1e-3)},
                      {"volume_drift", drift},
                      {"resident_mb", double(field.residentBytes()) / (1 << 20)},
                      {"note", "shared machine: timings are noisy"}};
  out << j.dump() << "\n" << std::flush;
  std::cerr << "erosion " << methodName(method) << " " << g.label() << " threads " << threads
            << ": " << median(rates) / 1e6 << " M cell-steps/s (" << median(cpuRates) / 1e6
            << " M per CPU-second, " << totalCpu / (totalMs * 1e-3) << " CPUs used), drift "
            << drift << "\n";
}

// Throughput on a sphere chart: noise per distinct point (twins, seam and pole rows one height).
// The closed surfaces' charts of these rows: lat-long, octahedral, torus, cylinder.
enum class Surface { kLatLong, kOctahedral, kTorus, kCylinder };

// One surface's field, ready to step (its first step, which loads every tile, done).
struct SurfaceRun {
  std::shared_ptr<const core::Chart> chart;
  std::unique_ptr<sand::SandField> field;
  double scale = 0, dt = 0, loadMs = 0, v0 = 0, totalMs = 0;
  std::size_t cells = 0;
  std::vector<double> rates, cpuRates;
};

std::shared_ptr<const core::Chart> surfaceChart(const core::GridSize& g, Surface surface) {
  const double R = g.m() / std::numbers::pi;  // lat-long's meridian spacing: 1 m
  // The tubes: 1 m steps round the tube, the default torus's r / R = 0.4, a cylinder as long
  // as its circumference.
  const double tubeR = g.m() / (2.0 * std::numbers::pi);
  if (surface == Surface::kOctahedral) return std::make_shared<core::OctahedralChart>(g, R);
  if (surface == Surface::kTorus) return std::make_shared<core::TorusChart>(g, 2.5 * tubeR, tubeR);
  if (surface == Surface::kCylinder)
    return std::make_shared<core::CylinderChart>(g, tubeR, double(g.m()));
  return std::make_shared<core::LatLongChart>(g, R);
}

sand::StepReport surfaceStep(SurfaceRun& s, Method method, const sand::Material& mat) {
  if (method == Method::kThermal) return s.field->thermalStep(mat);
  return s.field->diffusionStep(mat, s.dt,
                                method == Method::kSemiImplicit
                                    ? sand::DiffusionScheme::kSemiImplicit
                                    : sand::DiffusionScheme::kExplicit,
                                sand::StepPolicy::kRefuse);
}

SurfaceRun startSurface(int n, Surface surface, Method method, const sand::Material& mat) {
  const core::GridSize g(n);
  SurfaceRun s;
  s.chart = surfaceChart(g, surface);
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      // A hash of the canonical vertex's index (seeding a std::mt19937 per point took most of
      // the bench's time at 1025^2).
      const core::GridPoint c = s.chart->canonical(u, v);
      std::uint64_t x = std::uint64_t(g.index(c.u, c.v)) + 0x9e3779b97f4a7c15ull;
      x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
      x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
      x ^= x >> 31;
      h[g.index(u, v)] = 100.0f + float(-10.0 + 20.0 * double(x >> 11) * 0x1.0p-53);
    }
  }
  s.scale = sand::SandGrid(s.chart).absVolume(h);
  s.field = std::make_unique<sand::SandField>(s.chart, h);
  s.field->markAll();
  s.dt = s.field->explicitBound(mat) * (method == Method::kSemiImplicit ? 4.0 : 1.0);
  s.loadMs = timeMs([&] { surfaceStep(s, method, mat); });  // every tile (and its geometry)
  s.v0 = s.field->volume();
  return s;
}

// Every surface stepped once per repetition, the order rotated from one repetition to the next,
// so that the machine's drift falls on all of them alike; each surface's rate in a repetition is
// divided by lat-long's of the same repetition (the first surface), and the row reports the
// median of those ratios (`rate_ratio_vs_latlong`) beside the median rates.
void sphereThroughput(int n, const std::vector<Surface>& surfaces, Method method, int threads,
                      int repeats, std::ostream& out) {
  const sand::Material mat = sand::Material::sand();
  omp_set_num_threads(threads);
  std::vector<SurfaceRun> runs;
  for (Surface surface : surfaces) runs.push_back(startSurface(n, surface, method, mat));
  const std::size_t count = runs.size();
  for (int k = 0; k < repeats; ++k) {
    for (std::size_t j = 0; j < count; ++j) {
      SurfaceRun& s = runs[(j + std::size_t(k)) % count];
      sand::StepReport r;
      const double c0 = cpuSeconds();
      const double t = timeMs([&] { r = surfaceStep(s, method, mat); });
      s.rates.push_back(double(r.cells) / (t * 1e-3));
      s.cpuRates.push_back(double(r.cells) / std::max(cpuSeconds() - c0, 1e-9));
      s.cells += r.cells;
      s.totalMs += t;
    }
  }
  for (const SurfaceRun& s : runs) {
    std::vector<double> ratios, cpuRatios;
    for (int k = 0; k < repeats; ++k) {
      ratios.push_back(s.rates[std::size_t(k)] / runs[0].rates[std::size_t(k)]);
      cpuRatios.push_back(s.cpuRates[std::size_t(k)] / runs[0].cpuRates[std::size_t(k)]);
    }
    const double drift = std::abs(s.field->volume() - s.v0) / s.scale;
    const core::GridSize& g = s.chart->grid();
    nlohmann::json j = {
        {"bench", "erosion"},
        {"method", methodName(method)},
        {"chart", s.chart->name()},
        {"grid", g.label()},
        {"threads", threads},
        {"steps", repeats},
        {"dt", method == Method::kThermal ? 0.0 : s.dt},
        {"cells_per_step", s.cells / std::size_t(std::max(1, repeats))},
        {"cell_steps_per_s", median(s.rates)},
        {"rate_ratio_vs_latlong", median(ratios)},
        {"rate_ratio_vs_latlong_min", *std::min_element(ratios.begin(), ratios.end())},
        {"rate_ratio_vs_latlong_max", *std::max_element(ratios.begin(), ratios.end())},
        {"cell_steps_per_cpu_s", median(s.cpuRates)},
        {"cpu_rate_ratio_vs_latlong", median(cpuRatios)},
        {"ms_per_step", s.totalMs / repeats},
        {"first_step_ms", s.loadMs},
        {"volume_drift", drift},
        {"resident_mb", double(s.field->residentBytes()) / (1 << 20)},
        {"note",
         "planet radius m/pi m; the charts stepped in turn, ratio per repetition; "
         "shared machine: timings are noisy"}};
    out << j.dump() << "\n" << std::flush;
    std::cerr << "erosion " << methodName(method) << " " << s.chart->name() << " " << g.label()
              << " threads " << threads << ": " << median(s.rates) / 1e6 << " M cell-steps/s, "
              << s.totalMs / repeats << " ms a step, x" << median(ratios)
              << " lat-long's rate (median of the repetitions; per CPU-second x"
              << median(cpuRatios) << "), drift " << drift << "\n";
  }
}

// `undo`: the live configuration, the settler reporting what it writes to the pipeline's undo
// journal (Settler::attachUndo); the row then says whether undo gives back the start bit for bit.
void crater(bool sphere, bool quick, int threads, std::ostream& out, bool octahedral = false,
            bool undo = false) {
  std::shared_ptr<const core::Chart> chart;
  double r, depth, base;
  if (sphere && octahedral) {
    chart = std::make_shared<core::OctahedralChart>(core::GridSize(quick ? 9 : 11), 6372790.0);
    r = 200e3;
    depth = 80e3;
    base = 0.0;
  } else if (sphere) {
    chart = std::make_shared<core::LatLongChart>(core::GridSize(quick ? 9 : 11), 6372790.0);
    r = 200e3;
    depth = 80e3;
    base = 0.0;
  } else {
    chart = std::make_shared<core::FlatChart>(core::GridSize(quick ? 8 : 10), 1.0, 1.0);
    r = 16.0;
    depth = 12.0;
    base = 20.0;
  }
  const core::GridSize g = chart->grid();
  terrain::Terrain t(chart, std::vector<float>(g.count(), float(base)));
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(undo);
  omp_set_num_threads(threads);
  const std::size_t budget = std::size_t(1) << 20;
  sand::Settler settler(t, sand::Material::sand(), {.cellBudget = budget});
  if (undo) settler.attachUndo(&pipe);
  const std::vector<float> start(t.heights().begin(), t.heights().end());
  sand::DisplacementTool tool(chart, {.radius = r}, &settler);
  const sand::SandGrid grid(chart);
  const double v0 = grid.volume(t.heights());
  Eigen::Vector3d at;
  if (sphere) {
    at = (chart->sphereRadius() + base + r - depth) *
         Eigen::Vector3d(0.5, 0.5, std::sqrt(0.5)).normalized();
  } else {
    at = Eigen::Vector3d(0.5 * g.m(), 0.5 * g.m(), base + r - depth);
  }
  const double stampMs = timeMs([&] { pipe.apply(tool, {at, 0.0}); });
  std::vector<double> frameMs;
  int frames = 0, steps = 0;
  std::size_t cellSteps = 0, boundsVertices = 0;
  while (frames < 100000) {
    const sand::FrameReport f = settler.frame();
    ++frames;
    steps += f.steps;
    cellSteps += f.cellSteps;
    boundsVertices += f.boundsVertices;
    frameMs.push_back(f.totalMs);
    if (f.atRest) break;
  }
  const double drift = std::abs(grid.volume(t.heights()) - v0) / grid.absVolume(t.heights());
  const double journalMb = double(pipe.journal().bytes()) / double(1 << 20);
  bool restored = false;
  if (undo) {
    pipe.undo();
    restored = std::equal(
        start.begin(), start.end(), t.heights().begin(), t.heights().end(), [](float a, float b) {
          return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
        });
  }
  nlohmann::json j = {
      {"bench", "erosion"},
      {"method", "crater-settle"},
      {"undo_journal", undo},
      {"journal_mb", journalMb},
      {"chart", chart->name()},
      {"grid", g.label()},
      {"threads", threads},
      {"tool_radius_m", r},
      {"depth_m", depth},
      {"removed_m3", tool.lastStats().removedVolume},
      {"stamp_ms", stampMs},
      {"budget_cell_steps", budget},
      {"frames", frames},
      {"steps", steps},
      {"cell_steps", cellSteps},
      {"cell_steps_per_s",
       double(cellSteps) / (std::accumulate(frameMs.begin(), frameMs.end(), 0.0) * 1e-3)},
      {"frame_ms_median", median(frameMs)},
      {"frame_ms_max", *std::max_element(frameMs.begin(), frameMs.end())},
      {"bounds_vertices", boundsVertices},
      {"volume_drift", drift},
      {"note", "volume_drift of the float heights; shared machine: timings are noisy"}};
  if (undo) j["undo_restores_start"] = restored;
  out << j.dump() << "\n" << std::flush;
  std::cerr << "erosion crater " << chart->name() << " " << g.label() << " threads " << threads
            << (undo ? " undo journal" : "") << ": " << frames << " frames, " << steps
            << " steps, median frame " << median(frameMs) << " ms"
            << (undo ? restored ? ", undo restores the start" : ", UNDO DOES NOT RESTORE" : "")
            << "\n";
}

}  // namespace

// `bench erosion-charts --method M --sphere-only`: one method's rows, lat-long and octahedral
// alone (the comparison of two builds in turn on a shared machine).
struct ChartsSettings {
  std::string method;  // "" = all three
  bool sphereOnly = false;
};

// The sphere: lat-long, octahedral, torus and cylinder stepped in turn in one run (the glued
// charts' per-cell loops against lat-long's rows). Also `bench erosion-charts` alone.
void benchErosionCharts(const BenchOptions& options, const ChartsSettings& only,
                        std::ostream& out) {
  const int saved = omp_get_max_threads();
  const int repeats =
      std::max(3, options.quick ? std::min(options.repeats, 5) : std::min(options.repeats, 9));
  const int ns = options.quick ? 8 : 10;
  std::vector<Surface> surfaces = {Surface::kLatLong, Surface::kOctahedral};
  if (!only.sphereOnly) surfaces.insert(surfaces.end(), {Surface::kTorus, Surface::kCylinder});
  for (Method method : {Method::kThermal, Method::kExplicit, Method::kSemiImplicit}) {
    if (!only.method.empty() && only.method != methodName(method)) continue;
    for (int threads : {1, 2}) sphereThroughput(ns, surfaces, method, threads, repeats, out);
  }
  omp_set_num_threads(saved);
}

void benchErosionCharts(const BenchOptions& options, std::ostream& out) {
  benchErosionCharts(options, ChartsSettings{}, out);
}

void benchErosion(const BenchOptions& options, std::ostream& out) {
  const int saved = omp_get_max_threads();
  const int n = options.quick ? 9 : 11;
  const int repeats =
      std::max(3, options.quick ? std::min(options.repeats, 5) : std::min(options.repeats, 9));
  for (Method method : {Method::kThermal, Method::kExplicit, Method::kSemiImplicit}) {
    for (int threads : {1, 2}) throughput(n, method, threads, repeats, out);
  }
  for (bool sphere : {false, true}) {
    for (int threads : {1, 2}) crater(sphere, options.quick, threads, out);
  }
  benchErosionCharts(options, out);
  for (int threads : {1, 2}) {
    for (bool undo : {false, true}) crater(true, options.quick, threads, out, true, undo);
  }
  omp_set_num_threads(saved);
}

static const BenchRegistration kErosion(
    "erosion", "The sand core's throughput and the frames a crater needs to settle", benchErosion);
static const BenchRegistration kErosionCharts(
    "erosion-charts", "The sand core's rate on the four sphere charts in turn, ratios to lat-long",
    [](CLI::App& command) -> BenchFunction {
      auto only = std::make_shared<ChartsSettings>();
      command.add_option("--method", only->method, "Only this method's rows")
          ->check(CLI::IsMember({"thermal", "diffusion-explicit", "diffusion-implicit"}));
      command.add_flag("--sphere-only", only->sphereOnly,
                       "Lat-long and octahedral only (no torus, no cylinder)");
      return
          [only](const BenchOptions& o, std::ostream& out) { benchErosionCharts(o, *only, out); };
    });

}  // namespace ps::bench
