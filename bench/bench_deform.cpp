// `planetsculpt bench deform`: paper 003's Tables 1-3 reproduced. Grids 2049^2, 4097^2 and
// 8193^2 (--quick: 2049^2 only), the control vertex on the u = 0 meridian (the seam: the paper's
// worst case) at "latitudes" 0, 30, ..., 180 degrees counted from one pole (v = 0) to the other
// (v = m), radii of deformation 150, 300 and 600 km on a 6,372.79 km planet, the paper's
// sigma = 0.17 and mu = 1. Per cell, medians over the repeats of one edit through the whole
// pipeline (undo off): grow_ms (control vertex + region growing), heights_ms (Gaussian), errors_ms
// (Terrain::commitEdit, the hierarchical bounds update), total_ms; and brush_only_ms, the same
// Gaussian evaluated for the same number of vertices in one flat array (the work no method can
// skip), with the same OpenMP threads. modified_vertices counts grid entries as the paper does
// (seam twins and every entry of a pole row); bruteforce_vertices is a scan of the whole grid
// with the same predicate; grow_heights_ms and ratio_without_errors isolate the edit layer's own
// work from the bounds update (src/terrain); paper_vertices and paper_frame_ms are the paper's
// table entries (its times are whole rendered frames, deformation included).
#include <omp.h>

#include <CLI/CLI.hpp>
#include <array>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/region_growing.hpp"
#include "terrain/terrain.hpp"

namespace ps::bench {

namespace {

constexpr double kPlanetRadius = 6372790.0;  // paper 003
constexpr std::array<double, 3> kRadiiKm = {150, 300, 600};

struct PaperRow {
  int latitude;
  std::array<double, 3> frameS;  // average frame time (s) for r = 150, 300, 600 km
  std::array<long, 3> vertices;  // modified vertices
};

// Paper 003, Tables 1 (2049^2), 2 (4097^2) and 3 (8193^2).
const std::map<int, std::array<PaperRow, 7>>& paperTables() {
  static const std::map<int, std::array<PaperRow, 7>> t = {
      {2049,
       {{{0, {0.064, 0.096, 0.117}, {32764, 63471, 126700}},
         {30, {0.041, 0.047, 0.051}, {698, 2789, 11467}},
         {60, {0.041, 0.047, 0.044}, {397, 1593, 6650}},
         {90, {0.041, 0.046, 0.043}, {360, 1431, 5737}},
         {120, {0.038, 0.044, 0.050}, {405, 1629, 6560}},
         {150, {0.045, 0.047, 0.050}, {704, 2916, 11543}},
         {180, {0.063, 0.086, 0.116}, {32759, 63463, 126888}}}}},
      {4097,
       {{{0, {0.117, 0.211, 0.368}, {126955, 253855, 503383}},
         {30, {0.043, 0.050, 0.067}, {2808, 11356, 45087}},
         {60, {0.043, 0.046, 0.048}, {1672, 6540, 25920}},
         {90, {0.041, 0.043, 0.048}, {1403, 5660, 22484}},
         {120, {0.041, 0.043, 0.049}, {1627, 6518, 26389}},
         {150, {0.044, 0.047, 0.065}, {2756, 11267, 45102}},
         {180, {0.116, 0.203, 0.369}, {126959, 253755, 503400}}}}},
      {8193,
       {{{0, {0.356, 0.711, 1.328}, {507744, 1006861, 2013967}},
         {30, {0.052, 0.053, 0.114}, {11302, 45437, 180019}},
         {60, {0.045, 0.052, 0.098}, {6532, 25752, 106635}},
         {90, {0.035, 0.047, 0.082}, {5765, 23056, 89330}},
         {120, {0.046, 0.051, 0.083}, {6511, 26024, 101521}},
         {150, {0.045, 0.059, 0.107}, {11329, 45625, 179929}},
         {180, {0.350, 0.720, 1.333}, {507805, 1007216, 2013721}}}}},
  };
  return t;
}

// A cheap planet: a few sines of the vertex direction (seam twins, pole rows and folded twins
// agree), on lat-long or the octahedral chart.
std::unique_ptr<terrain::Terrain> benchPlanet(int n, bool octahedral) {
  std::shared_ptr<const core::Chart> chart;
  if (octahedral)
    chart = std::make_shared<core::OctahedralChart>(core::GridSize(n), kPlanetRadius);
  else
    chart = std::make_shared<core::LatLongChart>(core::GridSize(n), kPlanetRadius);
  const core::GridSize g = chart->grid();
  std::vector<float> h(g.count());
#pragma omp parallel for schedule(static)
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const Eigen::Vector3d d = chart->up(u, v);
      h[g.index(u, v)] = float(2500.0 * std::sin(3.0 * d.x() + 1.0) * std::cos(2.0 * d.y() - 0.5) +
                               900.0 * std::sin(11.0 * d.z() + 4.0 * d.x()) +
                               150.0 * std::sin(40.0 * d.y()) * std::cos(37.0 * d.z()));
    }
  }
  return std::make_unique<terrain::Terrain>(chart, std::move(h));
}

// The unavoidable work: the Gaussian for `d2.size()` vertices in one flat array, applied to
// heights the way the brush does (double, clamp, float), same threads and threshold.
double brushOnlyMs(const edit::GaussianProfile& profile, double amount,
                   const std::vector<double>& d2, std::vector<float>& h, double limit) {
  const std::size_t n = d2.size();
  const bool parallel = n > 8192;
  auto apply = [&](std::size_t i) {
    const double w = amount * profile.fromDistance2(d2[i]);
    h[i] = static_cast<float>(std::clamp(double(h[i]) + w, -limit, limit));
  };
  return timeMs([&] {
    if (parallel) {
#pragma omp parallel for schedule(static)
      for (std::size_t i = 0; i < n; ++i) apply(i);
    } else {  // like the brush: small runs do not enter the OpenMP runtime
      for (std::size_t i = 0; i < n; ++i) apply(i);
    }
  });
}

}  // namespace

// `--chart`, `--side`, `--latitude`: one chart's cells, of one grid, at one latitude alone, for
// profiling one cell (with --repeats). Empty / 0 / -1: all.
struct DeformSettings {
  std::string chart;
  int side = 0;
  int latitude = -1;
};

void benchDeform(const BenchOptions& options, const DeformSettings& only, std::ostream& out) {
  const std::vector<int> levels =
      options.quick ? std::vector<int>{11} : std::vector<int>{11, 12, 13};
  const int repeats = std::max(1, options.quick ? std::min(options.repeats, 5) : options.repeats);
  for (const int n : levels) {
    const int side = (1 << n) + 1, m = 1 << n;
    // The worst cell of each chart in this run (issue 28: the octahedral chart's worst cell at
    // most a quarter of lat-long's).
    std::map<std::string, double> worstMs;
    if (only.side != 0 && only.side != side) continue;
    for (const bool octahedral : {false, true}) {
      if (!only.chart.empty() && only.chart != (octahedral ? "octahedral" : "latlong")) continue;
      std::cerr << "deform: building the " << side << "^2 "
                << (octahedral ? "octahedral" : "lat-long") << " planet ... " << std::flush;
      std::unique_ptr<terrain::Terrain> planet;
      const double buildMs = timeMs([&] { planet = benchPlanet(n, octahedral); });
      std::cerr << buildMs / 1000 << " s\n";
      edit::EditPipeline pipe(*planet);
      pipe.setUndoEnabled(false);
      const auto& paper = paperTables().at(side);
      // The same points of the sphere on both charts: lat-long's cells on the u = 0 meridian
      // (180 degrees W), from the south pole to the north pole; on the octahedral chart the
      // southern half of that meridian is a folded side (x = -1) and the south pole its corners.
      const core::LatLongChart latLong(core::GridSize(n), kPlanetRadius);
      for (const PaperRow& row : paper) {
        if (only.latitude >= 0 && row.latitude != only.latitude) continue;
        const int v = int(std::lround(double(row.latitude) * m / 180.0));
        const Eigen::Vector3d tool = latLong.position(0, v, 0.0);
        for (std::size_t ri = 0; ri < kRadiiKm.size(); ++ri) {
          edit::BrushSettings s;
          s.radius = kRadiiKm[ri] * 1000.0;
          s.sigma = 0.17;
          s.mu = 1.0;
          s.strength = 50.0;
          edit::GaussianBrush brush(s);
          pipe.apply(brush, {tool, 0.0});  // warm-up
          std::vector<double> grow, heights, errors, total, growHeights;
          edit::EditReport rep;
          for (int k = 0; k < repeats; ++k) {
            s.mode = (k % 2 == 0) ? edit::BrushMode::kLower : edit::BrushMode::kRaise;
            brush.setSettings(s);
            rep = pipe.apply(brush, {tool, 0.0});
            grow.push_back(rep.growMs);
            heights.push_back(rep.heightsMs);
            errors.push_back(rep.errorsMs);
            total.push_back(rep.totalMs);
            growHeights.push_back(rep.growMs + rep.heightsMs);
          }
          // The same Gaussian, the same vertices' distances, in one flat array.
          const edit::Region& region = pipe.lastRegion();
          std::vector<double> d2;
          d2.reserve(region.vertexCount());
          region.forEachSpan([&](int rv, int a, int b) {
            for (int u = a; u <= b; ++u) d2.push_back(pipe.field().distance2(u, rv));
          });
          std::vector<float> flat(d2.size(), 100.0f);
          const edit::GaussianProfile profile(s.radius, s.sigma, s.mu);
          std::vector<double> brushOnly;
          for (int k = 0; k < repeats; ++k) {
            brushOnly.push_back(brushOnlyMs(profile, s.strength, d2, flat, planet->heightLimit()));
          }
          const std::size_t brute = edit::bruteForceRegion(pipe.field(), s.radius);
          const double totalMs = median(total), brushMs = median(brushOnly),
                       errorsMs = median(errors);
          worstMs[planet->chart().name()] = std::max(worstMs[planet->chart().name()], totalMs);
          nlohmann::json j = {
              {"bench", "deform"},
              {"chart", planet->chart().name()},
              {"grid", side},
              {"latitude", row.latitude},
              {"r_km", kRadiiKm[ri]},
              {"control_u", rep.control.u},
              {"control_v", rep.control.v},
              {"modified_vertices", rep.modifiedVertices},
              {"distinct_points", rep.modifiedPoints},
              {"bruteforce_vertices", brute},
              {"paper_vertices", row.vertices[ri]},
              {"grow_ms", median(grow)},
              {"heights_ms", median(heights)},
              {"errors_ms", errorsMs},
              {"total_ms", totalMs},
              {"brush_only_ms", brushMs},
              {"ratio", brushMs > 0 ? totalMs / brushMs : 0.0},
              {"grow_heights_ms", median(growHeights)},
              {"ratio_without_errors", brushMs > 0 ? median(growHeights) / brushMs : 0.0},
              {"errors_share", totalMs > 0 ? errorsMs / totalMs : 0.0},
              {"bounds_vertices", rep.boundsVertices},
              {"paper_frame_ms", 1000.0 * row.frameS[ri]},
              {"repeats", repeats},
              {"threads", omp_get_max_threads()},
              {"error_rule", terrain::toString(planet->bounds().rule())}};
          out << j.dump() << "\n" << std::flush;
          std::cerr << "deform " << planet->chart().name() << " " << side << " lat " << row.latitude
                    << " r " << kRadiiKm[ri] << " km: " << rep.modifiedVertices
                    << " vertices (brute force " << brute << ", paper " << row.vertices[ri]
                    << "), total " << totalMs << " ms (errors " << errorsMs << "), brush only "
                    << brushMs << " ms\n";
        }
      }
    }
    out << nlohmann::json{{"bench", "deform"},
                          {"case", "worst_cells"},
                          {"grid", side},
                          {"latlong_worst_ms", worstMs["latlong"]},
                          {"octahedral_worst_ms", worstMs["octahedral"]},
                          {"octahedral_over_latlong",
                           worstMs["latlong"] > 0 ? worstMs["octahedral"] / worstMs["latlong"]
                                                  : 0.0}}
               .dump()
        << "\n"
        << std::flush;
  }
}

static const BenchRegistration kDeform(
    "deform", "Paper 003's tables: one brush edit through the pipeline per grid, latitude, radius",
    [](CLI::App& command) -> BenchFunction {
      auto only = std::make_shared<DeformSettings>();
      command.add_option("--chart", only->chart, "Only this chart's cells")
          ->check(CLI::IsMember({"latlong", "octahedral"}));
      command.add_option("--side", only->side, "Only this grid's cells (--quick runs 2049 only)")
          ->check(CLI::IsMember({2049, 4097, 8193}));
      command.add_option("--latitude", only->latitude, "Only the cells at this latitude (degrees)")
          ->check(CLI::IsMember({0, 30, 60, 90, 120, 150, 180}));
      return [only](const BenchOptions& o, std::ostream& out) { benchDeform(o, *only, out); };
    });

}  // namespace ps::bench
