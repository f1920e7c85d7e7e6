// `planetsculpt bench sand-tin`: the sand TIN (paper 000, sand::TinSand) in the paper's
// experiments and side by side with the grid core (sand::SandField) on the same strokes.
//
// The scene (the paper's flat sand): a 10 m x 10 m box of sand 1 m deep; a disc tool of radius
// 0.25 m (24 corners, rim 5 %, rampart one radius wide) pulled along the box's diagonal with its
// bottom 0.15 m under the sand's surface, a stamp every quarter radius; after each stamp two
// erosion iterations and the removal of redundant vertices (the paper's loop, Section 4).
//   experiment size (Figures 7, 9): the trace 0.55 of the diagonal, the TIN started from a
//     regular n x n grid of points (n^2 = 2.5 k .. 80 k vertices): time of each part
//     (stamping, erosion, redundancy detection, vertex removal), vertex and triangle counts.
//   experiment trace (Figures 8, 10): a 10,000-vertex TIN, the trace 0.1 .. 0.85 of the diagonal.
//   experiment compare: the same stroke (0.55) on grids of 129^2 .. 1025^2 (the grid core: the
//     same press and rampart on its float heights, then SandField's thermal erosion) and on the
//     TIN started from 5 x 5 points (it grows where the tool went), with and without erosion.
//     surface_error_m is the RMS difference from the finest grid's surface (1025^2; --quick
//     513^2) over that grid's vertices (surface_error_max_m the largest: a wall one cell off
//     makes it the tool's depth whatever the model); steepest_slope the steepest edge (the
//     TIN) or link (the grid): how sharp an imprint each holds.
//   experiment compare-exact: the same stroke as a press only (no rampart, no erosion) on the
//     TIN and on grids of 129^2 .. 8193^2 holding the exact shape at their vertices, each
//     measured against the exact stamped shape (the minimum over the stamps of the tool's shape)
//     on a 16384^2 lattice near the stroke and 1024^2 elsewhere: RMS over the box and largest.
//   Every comparison's TIN row: the grids' memory at the TIN's error (log-log between the grids
//     either side) and the ratio TIN / that (issue 27's target: at most 1/5).
//   experiment drift: one deep stamp into a 10,000-vertex TIN, then 10^4 erosion iterations
//     with the removal on (--quick: 10^3): the relative volume drift.
// Every row: "model" ("tin" or "grid"), vertices, memory_bytes (the TIN: its triangulation's
// containers; the grid: its float heights and the sand field's resident tiles), surface_error_m,
// volume_drift (|V_end - V_start| / V_start, each model's own V), ms. The scene and the stroke on
// each model are bench/sand_tin_strokes.cpp.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "app/bench_plots.hpp"
#include "app/plot.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/sand_tin_strokes.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "sand/sand_field.hpp"
#include "sand/tin_sand.hpp"
#include "tin/triangle_error.hpp"

// In the namespace of the experiments' helpers (sand_tin_strokes.hpp), which it uses throughout.
namespace ps::bench::sandtin {

namespace {

nlohmann::json tinRow(const std::string& experiment, const TinRun& r, double trace, int startN) {
  const auto& t = r.sand->tin();
  const auto& timing = r.sand->timing();
  return {{"bench", "sand-tin"},
          {"model", "tin"},
          {"experiment", experiment},
          {"start_vertices", startN * startN},
          {"trace", trace},
          {"stamps", r.stamps},
          {"erosion_steps", r.erosionSteps},
          {"vertices", t.vertexCount()},
          {"triangles", t.triangleCount()},
          {"constrained_edges", t.constrainedEdgeCount()},
          {"removed_vertices", r.removed},
          {"memory_bytes", t.memoryBytes()},
          {"bytes_per_vertex", double(t.memoryBytes()) / double(t.vertexCount())},
          {"vertex_slots", t.slots().vertexSlots},
          {"face_slots", t.slots().faceSlots},
          {"volume_drift", r.drift},
          {"stamp_ms", timing.stampMs},
          {"erosion_ms", timing.erodeMs},
          {"detect_ms", timing.detectMs},
          {"removal_ms", timing.removeMs},
          {"ms", r.ms}};
}

void sizeAndTrace(const BenchOptions& options, const Scene& scene, std::ostream& out,
                  std::vector<nlohmann::json>& rows) {
  const std::vector<int> sides =
      options.quick ? std::vector<int>{50, 100} : std::vector<int>{50, 71, 100, 142, 200, 283};
  for (const int n : sides) {
    std::cerr << "sand-tin: size " << n * n << "\n";
    const TinRun r = runTin(scene, n, 0.55, true);
    nlohmann::json row = tinRow("size", r, 0.55, n);
    row["surface_error_m"] = nullptr;
    rows.push_back(row);
    out << row.dump() << std::endl;
  }
  const std::vector<double> traces = options.quick
                                         ? std::vector<double>{0.2, 0.55}
                                         : std::vector<double>{0.1, 0.2, 0.3, 0.4, 0.55, 0.7, 0.85};
  for (const double trace : traces) {
    std::cerr << "sand-tin: trace " << trace << "\n";
    const TinRun r = runTin(scene, 100, trace, true);
    nlohmann::json row = tinRow("trace", r, trace, 100);
    row["surface_error_m"] = nullptr;
    rows.push_back(row);
    out << row.dump() << std::endl;
  }
}

// A grid's memory at a given surface error: log-log interpolation between the two grids whose
// errors lie on either side (extrapolated from the nearest two when none do). `grids`: (error,
// memory) pairs in order of growing memory.
struct AtError {
  double memory = NAN;
  bool extrapolated = false;
  std::string between;
};
AtError gridMemoryAt(const std::vector<std::pair<double, double>>& grids, double error,
                     const std::vector<std::string>& names) {
  AtError out;
  if (grids.size() < 2 || !(error > 0)) return out;
  std::size_t i = grids.size() - 2;  // below every grid's error: the finest two
  bool found = false;
  for (std::size_t k = 0; k + 1 < grids.size() && !found; ++k)
    if (grids[k].first >= error && error >= grids[k + 1].first) i = k, found = true;
  if (!found && error > grids.front().first) i = 0;
  out.extrapolated = !found;
  const double e0 = std::log(grids[i].first), e1 = std::log(grids[i + 1].first);
  const double m0 = std::log(grids[i].second), m1 = std::log(grids[i + 1].second);
  const double t = (std::log(error) - e0) / (e1 - e0);
  out.memory = std::exp(m0 + t * (m1 - m0));
  out.between = names[i] + " and " + names[i + 1];
  return out;
}

// Adds the TIN's memory against the grids' at its error to the TIN row of one experiment.
void equalErrorRatio(nlohmann::json& tinRowJson, const std::vector<nlohmann::json>& rows,
                     const std::string& experiment, const char* errorKey) {
  std::vector<std::pair<double, double>> grids;
  std::vector<std::string> names;
  for (const auto& r : rows)
    if (r["experiment"] == experiment && r["model"] == "grid" && r["reference"] != "itself")
      grids.emplace_back(r[errorKey].get<double>(), r["memory_bytes"].get<double>()),
          names.push_back(r["grid"].get<std::string>());
  const AtError at = gridMemoryAt(grids, tinRowJson[errorKey].get<double>(), names);
  const std::string suffix = std::string(errorKey) == "surface_error_m" ? "" : "_by_max";
  tinRowJson["grid_memory_at_equal_error_bytes" + suffix] = at.memory;
  tinRowJson["memory_ratio_at_equal_error" + suffix] =
      tinRowJson["memory_bytes"].get<double>() / at.memory;
  tinRowJson["equal_error_between" + suffix] = at.between;
  tinRowJson["equal_error_extrapolated" + suffix] = at.extrapolated;
}

// The press-only stroke (no rampart, no erosion) on the TIN and on grids of 129^2 .. 8193^2
// (--quick: .. 2049^2), each measured against the exact shape over a lattice 16384^2 across the
// box (--quick: 8192^2) within a band about the stroke (where the surfaces can differ) and a
// 1024^2 lattice over the rest of the box; RMS over the box's area and the largest difference.
void compareExact(const BenchOptions& options, const Scene& scene, std::ostream& out,
                  std::vector<nlohmann::json>& rows) {
  std::cerr << "sand-tin: compare against the exact shape (press only)\n";
  const double trace = 0.55;
  sand::TinStampTool tool = sand::TinStampTool::disc(scene.radius);
  tool.pushAside = false;
  const ExactStroke exact(scene, tool, trace);
  const TinRun t = runTin(scene, 5, trace, false, false);
  std::vector<ExactGrid> grids;
  std::vector<double> gridMs;
  const int finest = options.quick ? 11 : 13;
  for (int n = 7; n <= finest; ++n) {
    gridMs.push_back(timeMs([&] { grids.push_back(exactGrid(scene, exact, n)); }));
  }
  const std::size_t models = grids.size() + 1;  // the TIN last
  std::vector<double> sum2(models, 0.0), worst(models, 0.0), worstOutside(models, 0.0);
  const auto modelAt = [&](std::size_t m, double x, double y) {
    return m < grids.size() ? grids[m].at(x, y) : t.sand->tin().heightAt({x, y});
  };
  // The band: where a grid's cell or the TIN's triangles can meet a stamp.
  const double band = exact.outerRadius + 2.0 * grids.front().d;
  const int fine = options.quick ? 8192 : 16384, coarse = 1024;
  std::size_t bandSamples = 0;
  const double ms = timeMs([&] {
    const double s = scene.side / fine;
    for (int j = 0; j < fine; ++j)
      for (int i = 0; i < fine; ++i) {
        const Eigen::Vector2d x((i + 0.5) * s, (j + 0.5) * s);
        if (exact.distanceToStroke(x) > band) continue;
        ++bandSamples;
        const double e = exact.at(x);
        for (std::size_t m = 0; m < models; ++m) {
          const double diff = modelAt(m, x.x(), x.y()) - e;
          sum2[m] += diff * diff * s * s;
          worst[m] = std::max(worst[m], std::abs(diff));
        }
      }
    const double c = scene.side / coarse;
    for (int j = 0; j < coarse; ++j)
      for (int i = 0; i < coarse; ++i) {
        const Eigen::Vector2d x((i + 0.5) * c, (j + 0.5) * c);
        if (exact.distanceToStroke(x) <= band) continue;
        const double e = exact.at(x);
        for (std::size_t m = 0; m < models; ++m) {
          const double diff = modelAt(m, x.x(), x.y()) - e;
          sum2[m] += diff * diff * c * c;
          worstOutside[m] = std::max(worstOutside[m], std::abs(diff));
        }
      }
  });
  const double area = scene.side * scene.side;
  const std::string reference =
      "exact stamped shape (press only: no rampart, no erosion), lattice " + std::to_string(fine) +
      "^2 within " + core::exactNumber(band) + " m of the stroke, " + std::to_string(coarse) +
      "^2 elsewhere";
  for (std::size_t m = 0; m < grids.size(); ++m) {
    const ExactGrid& g = grids[m];
    nlohmann::json row = {{"bench", "sand-tin"},
                          {"model", "grid"},
                          {"experiment", "compare-exact"},
                          {"grid", std::to_string(g.side) + "x" + std::to_string(g.side)},
                          {"vertices", std::size_t(g.side) * g.side},
                          {"memory_bytes", g.h.size() * sizeof(float)},
                          {"surface_error_m", std::sqrt(sum2[m] / area)},
                          {"surface_error_max_m", std::max(worst[m], worstOutside[m])},
                          {"surface_error_max_outside_band_m", worstOutside[m]},
                          {"reference", reference},
                          {"volume_drift", nullptr},
                          {"steepest_slope", nullptr},
                          {"ms", gridMs[m]}};
    rows.push_back(row);
    out << row.dump() << std::endl;
  }
  nlohmann::json row = tinRow("compare-exact", t, trace, 5);
  const std::size_t m = grids.size();
  row["surface_error_m"] = std::sqrt(sum2[m] / area);
  row["surface_error_max_m"] = std::max(worst[m], worstOutside[m]);
  row["surface_error_max_outside_band_m"] = worstOutside[m];
  row["reference"] = reference;
  row["volume_drift"] = nullptr;  // a press only: the volume is not kept
  row["steepest_slope"] = maxEdgeSlope(t.sand->tin());
  row["band_samples"] = bandSamples;
  row["measure_ms"] = ms;
  equalErrorRatio(row, rows, "compare-exact", "surface_error_m");
  equalErrorRatio(row, rows, "compare-exact", "surface_error_max_m");
  rows.push_back(row);
  out << row.dump() << std::endl;
}

void compare(const BenchOptions& options, const Scene& scene, std::ostream& out,
             std::vector<nlohmann::json>& rows) {
  const int finest = options.quick ? 9 : 10;
  for (const bool erosion : {false, true}) {
    std::cerr << "sand-tin: compare, erosion " << (erosion ? "on" : "off") << "\n";
    const GridRun reference = runGrid(scene, finest, 0.55, erosion);
    const char* experiment = erosion ? "compare-eroded" : "compare-imprint";
    for (int n = 7; n <= finest; ++n) {
      const GridRun g = n == finest ? GridRun{} : runGrid(scene, n, 0.55, erosion);
      const GridRun& run = n == finest ? reference : g;
      const auto [rms, worst] =
          surfaceError(reference, [&](double x, double y) { return run.at(x, y); });
      nlohmann::json row = {
          {"bench", "sand-tin"},
          {"model", "grid"},
          {"experiment", experiment},
          {"grid", std::to_string(run.side) + "x" + std::to_string(run.side)},
          {"vertices", std::size_t(run.side) * run.side},
          {"memory_bytes", run.memory},
          {"surface_error_m", rms},
          {"surface_error_max_m", worst},
          {"reference", n == finest ? "itself" : "finest grid"},
          {"volume_drift", run.drift},
          {"steepest_slope", gridSteepest(run)},
          {"ms_per_stamp", run.stampMs / double(run.stamps)},
          {"ms_per_erosion_step", run.erosionSteps ? run.erodeMs / double(run.erosionSteps) : 0.0},
          {"ms", run.ms}};
      rows.push_back(row);
      out << row.dump() << std::endl;
    }
    const TinRun t = runTin(scene, 5, 0.55, erosion);
    const auto [rms, worst] = surfaceError(reference, [&](double x, double y) {
      return t.sand->tin().heightAt({x, y});
    });
    nlohmann::json row = tinRow(experiment, t, 0.55, 5);
    row["surface_error_m"] = rms;
    row["surface_error_max_m"] = worst;
    row["reference"] = "finest grid";
    row["steepest_slope"] = maxEdgeSlope(t.sand->tin());
    row["ms_per_stamp"] = t.sand->timing().stampMs / double(t.stamps);
    row["ms_per_erosion_step"] =
        t.erosionSteps ? t.sand->timing().erodeMs / double(t.erosionSteps) : 0.0;
    equalErrorRatio(row, rows, experiment, "surface_error_m");
    rows.push_back(row);
    out << row.dump() << std::endl;
  }
}

void drift(const BenchOptions& options, const Scene& scene, std::ostream& out) {
  const int steps = options.quick ? 1000 : 10000;
  std::cerr << "sand-tin: drift over " << steps << " erosion steps\n";
  sand::TinSand s(flatTin(scene, 100));
  const double v0 = s.tin().volume();
  std::size_t removed = 0;
  const double ms = timeMs([&] {
    s.stamp({5.0, 5.0}, 0.3, sand::TinStampTool::disc(1.5));
    for (int k = 0; k < steps; ++k) {
      s.erode();
      removed += s.removeRedundant();
    }
  });
  out << nlohmann::json{{"bench", "sand-tin"},
                        {"model", "tin"},
                        {"experiment", "drift"},
                        {"erosion_steps", steps},
                        {"vertices", s.tin().vertexCount()},
                        {"removed_vertices", removed},
                        {"memory_bytes", s.tin().memoryBytes()},
                        {"surface_error_m", nullptr},
                        {"volume_drift", std::abs(s.tin().volume() - v0) / v0},
                        {"still_active", s.activeCount()},
                        {"valid", s.tin().isValid()},
                        {"ms", ms}}
             .dump()
      << std::endl;
}

void plots(const std::vector<nlohmann::json>& rows, const std::string& outDir) {
  // One series per column `keys[p]` (labelled `labels[p]`) of the experiment's rows, against x.
  const auto experimentSeries = [&](const char* experiment, const char* x,
                                    const std::vector<const char*>& keys,
                                    const std::vector<const char*>& labels) {
    std::vector<app::PlotSeries> out;
    for (std::size_t p = 0; p < keys.size(); ++p) {
      app::PlotSeries s;
      s.label = labels[p];
      s.colour = app::seriesColour(p);
      for (const auto& r : rows)
        if (r["experiment"] == experiment)
          s.x.push_back(app::jsonNumber(r, x)), s.y.push_back(app::jsonNumber(r, keys[p]));
      out.push_back(s);
    }
    return out;
  };
  const auto partSeries = [&](const char* experiment, const char* x) {
    return experimentSeries(experiment, x, {"stamp_ms", "erosion_ms", "detect_ms", "removal_ms"},
                            {"stamping", "erosion", "redundancy detection", "vertex removal"});
  };
  const auto countSeries = [&](const char* experiment, const char* x) {
    return experimentSeries(experiment, x, {"vertices", "triangles"}, {"vertices", "triangles"});
  };
  const std::vector<app::PlotPanel> times = {
      {"time per part (trace 0.55)", "TIN size (start vertices)", "ms, whole stroke", false, false,
       partSeries("size", "start_vertices")},
      {"time per part (10,000 vertices)", "trace length (of the diagonal)", "ms, whole stroke",
       false, false, partSeries("trace", "trace")}};
  const std::vector<app::PlotPanel> counts = {
      {"TIN after the stroke (trace 0.55)", "TIN size (start vertices)", "count", false, false,
       countSeries("size", "start_vertices")},
      {"TIN after the stroke (10,000 vertices)", "trace length (of the diagonal)", "count", false,
       false, countSeries("trace", "trace")}};
  const auto modelSeries = [&](const char* x, const char* y, bool skipReference) {
    std::vector<app::PlotSeries> out;
    std::size_t colour = 0;
    for (const char* experiment : {"compare-imprint", "compare-eroded", "compare-exact"})
      for (const char* model : {"grid", "tin"}) {
        app::PlotSeries s;
        const std::string e = experiment;
        s.label = std::string(model) + (e == "compare-imprint"  ? ", imprint"
                                        : e == "compare-eroded" ? ", eroded"
                                                                : ", press vs exact");
        s.colour = app::seriesColour(colour++);
        s.lines = std::string(model) == "grid";
        for (const auto& r : rows)
          if (r["experiment"] == experiment && r["model"] == model &&
              !(skipReference && r.contains("reference") && r["reference"] == "itself"))
            s.x.push_back(app::jsonNumber(r, x)), s.y.push_back(app::jsonNumber(r, y));
        out.push_back(s);
      }
    return out;
  };
  const std::vector<app::PlotPanel> memory = {
      {"memory against surface error", "RMS difference from the finest grid or exact shape (m)",
       "memory (bytes)", true, true, modelSeries("surface_error_m", "memory_bytes", true)},
      {"steepest wall against memory", "memory (bytes)", "steepest slope (rise / run)", true, true,
       modelSeries("memory_bytes", "steepest_slope", false)}};
  cv::Mat image;
  cv::vconcat(
      std::vector<cv::Mat>{app::drawPlots(times, 480, 330), app::drawPlots(counts, 480, 330),
                           app::drawPlots(memory, 480, 330)},
      image);
  cv::imwrite(outDir + "/sand_tin.png", image);
  std::cerr << "bench: wrote " << outDir << "/sand_tin.png\n";
}

// `--only PART,...`: only those experiments (empty: all).
void benchSandTin(const BenchOptions& options, const std::vector<std::string>& only,
                  std::ostream& out) {
  const Scene scene;
  std::vector<nlohmann::json> rows;
  const auto runs = [&](const char* part) {
    return only.empty() || std::find(only.begin(), only.end(), part) != only.end();
  };
  if (runs("size")) sizeAndTrace(options, scene, out, rows);
  if (runs("compare")) compare(options, scene, out, rows);
  if (runs("exact")) compareExact(options, scene, out, rows);
  if (runs("drift")) drift(options, scene, out);
  if (!options.outDir.empty()) plots(rows, options.outDir);
}

}  // namespace

static const BenchRegistration kSandTin(
    "sand-tin", "The sand TIN in paper 000's experiments, beside the grid core",
    [](CLI::App& command) -> BenchFunction {
      auto only = std::make_shared<std::vector<std::string>>();
      command.add_option("--only", *only, "Only these experiments (comma-separated)")
          ->delimiter(',')
          ->check(CLI::IsMember({"size", "compare", "exact", "drift"}));
      return [only](const BenchOptions& o, std::ostream& out) { benchSandTin(o, *only, out); };
    });

}  // namespace ps::bench::sandtin
