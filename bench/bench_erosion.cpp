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
// 4x it (on the glued charts along lines continued across the folds and seams). The planet crater
// runs on both charts too.
//
// The machine this was written on is shared with other builds: timings are noisy; compare runs
// taken back to back.
#include <omp.h>
#include <time.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <random>
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

void sphereThroughput(int n, Surface surface, Method method, int threads, int repeats,
                      std::ostream& out) {
  const core::GridSize g(n);
  const double R = g.m() / std::numbers::pi;  // lat-long's meridian spacing: 1 m
  // The tubes: 1 m steps round the tube, the default torus's r / R = 0.4, a cylinder as long
  // as its circumference.
  const double tubeR = g.m() / (2.0 * std::numbers::pi);
  std::shared_ptr<const core::Chart> chart;
  if (surface == Surface::kOctahedral) {
    chart = std::make_shared<core::OctahedralChart>(g, R);
  } else if (surface == Surface::kTorus) {
    chart = std::make_shared<core::TorusChart>(g, 2.5 * tubeR, tubeR);
  } else if (surface == Surface::kCylinder) {
    chart = std::make_shared<core::CylinderChart>(g, tubeR, double(g.m()));
  } else {
    chart = std::make_shared<core::LatLongChart>(g, R);
  }
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const core::GridPoint c = chart->canonical(u, v);
      std::mt19937 rng(std::uint32_t(g.index(c.u, c.v) * 2654435761u + 1234u));
      h[g.index(u, v)] = 100.0f + std::uniform_real_distribution<float>(-10.0f, 10.0f)(rng);
    }
  }
  const sand::SandGrid grid(chart);
  const double scale = grid.absVolume(h);
  sand::SandField field(chart, h);
  const sand::Material mat = sand::Material::sand();
  omp_set_num_threads(threads);
  field.markAll();
  const bool implicit = method == Method::kSemiImplicit;
  const double dt = field.explicitBound(mat) * (implicit ? 4.0 : 1.0);
  auto step = [&] {
    if (method == Method::kThermal) return field.thermalStep(mat);
    return field.diffusionStep(
        mat, dt, implicit ? sand::DiffusionScheme::kSemiImplicit : sand::DiffusionScheme::kExplicit,
        sand::StepPolicy::kRefuse);
  };
  const double loadMs = timeMs([&] { step(); });  // loads every tile (and its geometry)
  const double v0 = field.volume();
  std::vector<double> rates;
  std::size_t cells = 0;
  double totalMs = 0;
  for (int k = 0; k < repeats; ++k) {
    sand::StepReport r;
    const double t = timeMs([&] { r = step(); });
    rates.push_back(double(r.cells) / (t * 1e-3));
    cells += r.cells;
    totalMs += t;
  }
  const double drift = std::abs(field.volume() - v0) / scale;
  nlohmann::json j = {{"bench", "erosion"},
                      {"method", methodName(method)},
                      {"chart", chart->name()},
                      {"grid", g.label()},
                      {"threads", threads},
                      {"steps", repeats},
                      {"dt", method == Method::kThermal ? 0.0 : dt},
                      {"cells_per_step", cells / std::size_t(std::max(1, repeats))},
                      {"cell_steps_per_s", median(rates)},
                      {"ms_per_step", totalMs / repeats},
                      {"first_step_ms", loadMs},
                      {"volume_drift", drift},
                      {"resident_mb", double(field.residentBytes()) / (1 << 20)},
                      {"note", "planet radius m/pi m; shared machine: timings are noisy"}};
  out << j.dump() << "\n" << std::flush;
  std::cerr << "erosion " << methodName(method) << " " << chart->name() << " " << g.label()
            << " threads " << threads << ": " << median(rates) / 1e6 << " M cell-steps/s, "
            << totalMs / repeats << " ms a step, drift " << drift << "\n";
}

void crater(bool sphere, bool quick, int threads, std::ostream& out, bool octahedral = false) {
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
  pipe.setUndoEnabled(false);
  omp_set_num_threads(threads);
  const std::size_t budget = std::size_t(1) << 20;
  sand::Settler settler(t, sand::Material::sand(), {.cellBudget = budget});
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
  nlohmann::json j = {
      {"bench", "erosion"},
      {"method", "crater-settle"},
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
  out << j.dump() << "\n" << std::flush;
  std::cerr << "erosion crater " << chart->name() << " " << g.label() << " threads " << threads
            << ": " << frames << " frames, " << steps << " steps, median frame " << median(frameMs)
            << " ms\n";
}

}  // namespace

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
  // The sphere: lat-long and octahedral side by side, same run; then the torus and the cylinder
  // (the octahedral chart's per-cell loops).
  const int ns = options.quick ? 8 : 10;
  for (Method method : {Method::kThermal, Method::kExplicit, Method::kSemiImplicit}) {
    for (int threads : {1, 2}) {
      for (Surface surface :
           {Surface::kLatLong, Surface::kOctahedral, Surface::kTorus, Surface::kCylinder})
        sphereThroughput(ns, surface, method, threads, repeats, out);
    }
  }
  for (int threads : {1, 2}) crater(true, options.quick, threads, out, true);
  omp_set_num_threads(saved);
}

static const BenchRegistration kRegistered("erosion", benchErosion);

}  // namespace ps::bench
