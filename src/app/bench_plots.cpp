#include "app/bench_plots.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include "app/plot.hpp"
#include "io/heightmap_export.hpp"

namespace ps::app {

namespace {

std::string str(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : "";
}

// Records of one benchmark grouped by a label, in first-seen order.
std::vector<std::pair<std::string, std::vector<nlohmann::json>>> groups(
    const std::vector<nlohmann::json>& records, const std::string& bench,
    const std::function<std::string(const nlohmann::json&)>& label,
    const std::function<bool(const nlohmann::json&)>& keep = {}) {
  std::vector<std::pair<std::string, std::vector<nlohmann::json>>> out;
  for (const auto& r : records) {
    if (str(r, "bench") != bench || (keep && !keep(r))) continue;
    const std::string l = label(r);
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& g) { return g.first == l; });
    if (it == out.end()) {
      out.push_back({l, {}});
      it = out.end() - 1;
    }
    it->second.push_back(r);
  }
  return out;
}

PlotSeries series(const std::string& label, const std::vector<nlohmann::json>& rs, const char* x,
                  const char* y, std::size_t colour, bool lines = true) {
  PlotSeries s;
  s.label = label;
  s.colour = seriesColour(colour);
  s.lines = lines;
  std::vector<std::pair<double, double>> pts;
  for (const auto& r : rs) pts.emplace_back(jsonNumber(r, x), jsonNumber(r, y));
  if (lines) std::sort(pts.begin(), pts.end());
  for (const auto& [a, b] : pts) s.x.push_back(a), s.y.push_back(b);
  return s;
}

PlotSeries bound(const std::string& label, double lo, double hi) {
  PlotSeries s;
  s.label = label;
  s.colour = cv::Scalar(40, 40, 40);
  s.dashed = true;
  s.x = {lo, hi};
  s.y = {lo, hi};
  return s;
}

// Draws panels into DIR/name (a plot is drawn only when its bench's records are there).
using SavePlot = std::function<void(const std::vector<PlotPanel>&, const char* name)>;

// tessellate.png: time and triangles against the measured screen error, and that error against
// the dist_max bound.
void tessellationPlots(const std::vector<nlohmann::json>& records, const SavePlot& save) {
  const auto tess = groups(records, "tessellate",
                           [](const auto& r) { return str(r, "view") + " " + str(r, "grid"); });
  if (!tess.empty()) {
    PlotPanel time{"Tessellation time vs measured screen error",
                   "measured max screen error (px)",
                   "ms",
                   true,
                   true,
                   {}};
    PlotPanel err{"Measured error vs the guaranteed bound",
                  "dist_max requested (px)",
                  "measured max screen error (px)",
                  true,
                  true,
                  {}};
    PlotPanel tris{"Triangles vs measured screen error",
                   "measured max screen error (px)",
                   "triangles",
                   true,
                   true,
                   {}};
    double lo = 1e9, hi = 0;
    for (std::size_t i = 0; i < tess.size(); ++i) {
      time.series.push_back(series(tess[i].first, tess[i].second, "max_screen_error_px", "ms", i));
      err.series.push_back(
          series(tess[i].first, tess[i].second, "dist_max", "max_screen_error_px", i));
      tris.series.push_back(
          series(tess[i].first, tess[i].second, "max_screen_error_px", "triangles", i));
      for (const auto& r : tess[i].second) {
        lo = std::min(lo, jsonNumber(r, "dist_max")), hi = std::max(hi, jsonNumber(r, "dist_max"));
      }
    }
    err.series.push_back(bound("bound: error = dist_max", lo, hi));
    save({time, err, tris}, "tessellate.png");
  }
}

// tessellate_charts.png: the same relief on each chart.
void chartPlots(const std::vector<nlohmann::json>& records, const SavePlot& save) {
  const auto charts = groups(records, "tessellate_chart", [](const auto& r) {
    return str(r, "chart") + " " + str(r, "view") + " " + str(r, "grid");
  });
  if (!charts.empty()) {
    PlotPanel tris{"Triangles vs measured screen error, by chart",
                   "measured max screen error (px)",
                   "triangles",
                   true,
                   true,
                   {}};
    PlotPanel time{"Tessellation time vs measured screen error, by chart",
                   "measured max screen error (px)",
                   "ms",
                   true,
                   true,
                   {}};
    for (std::size_t i = 0; i < charts.size(); ++i) {
      tris.series.push_back(
          series(charts[i].first, charts[i].second, "max_screen_error_px", "triangles", i));
      time.series.push_back(
          series(charts[i].first, charts[i].second, "max_screen_error_px", "ms", i));
    }
    save({tris, time}, "tessellate_charts.png");
  }
}

// export.png: triangles and time against the measured true error, planetsculpt beside Martini,
// and the measured error against the requested one with its bound.
void exportPlots(const std::vector<nlohmann::json>& records, const SavePlot& save) {
  const auto exp = groups(
      records, "export",
      [](const auto& r) {
        const double threads = jsonNumber(r, "threads");
        return str(r, "tool") + (threads > 1 ? " 2 threads " : " ") + str(r, "heightmap");
      },
      [](const auto& r) {
        return str(r, "tool") == "planetsculpt" || str(r, "tool") == "martini";
      });
  if (!exp.empty()) {
    PlotPanel tris{
        "Export: triangles vs measured true error", "true error (m)", "triangles", true, true, {}};
    PlotPanel ms{"Export: time vs measured true error", "true error (m)", "ms", true, true, {}};
    PlotPanel err{"Measured vs requested error", "requested (m)", "true error (m)", true, true, {}};
    double lo = 1e30, hi = 0;
    for (std::size_t i = 0; i < exp.size(); ++i) {
      tris.series.push_back(series(exp[i].first, exp[i].second, "true_error_m", "triangles", i));
      ms.series.push_back(series(exp[i].first, exp[i].second, "true_error_m", "ms", i));
      err.series.push_back(
          series(exp[i].first, exp[i].second, "requested_error_m", "true_error_m", i));
      for (const auto& r : exp[i].second) {
        lo = std::min(lo, jsonNumber(r, "requested_error_m"));
        hi = std::max(hi, jsonNumber(r, "requested_error_m"));
      }
    }
    err.series.push_back(bound("bound (planetsculpt): true <= requested", lo, hi));
    save({tris, ms, err}, "export.png");
  }
}

// erosion.png: throughput against threads with the 100 M target, volume drift against step time
// with the 1e-9 target.
void erosionPlots(const std::vector<nlohmann::json>& records, const SavePlot& save) {
  const auto ero = groups(
      records, "erosion",
      [](const auto& r) {
        // Lat-long and octahedral rows share a method and a grid: the chart tells them apart
        // (rows written before it had one name none).
        const std::string chart = str(r, "chart");
        return str(r, "method") + " " + (chart.empty() || chart == "flat" ? "" : chart + " ") +
               str(r, "grid");
      },
      [](const auto& r) { return str(r, "method") != "crater-settle"; });
  if (!ero.empty()) {
    PlotPanel rate{"Erosion throughput", "threads", "M cell-steps/s", false, false, {}};
    PlotPanel drift{"Step time vs volume drift (0 drawn at 1e-17)",
                    "ms per step",
                    "relative volume drift",
                    true,
                    true,
                    {}};
    for (std::size_t i = 0; i < ero.size(); ++i) {
      auto rs = ero[i].second;
      for (auto& r : rs) {
        r["mcs"] = jsonNumber(r, "cell_steps_per_s") / 1e6;
        r["drift_shown"] = std::max(std::abs(jsonNumber(r, "volume_drift")), 1e-17);
      }
      rate.series.push_back(series(ero[i].first, rs, "threads", "mcs", i));
      drift.series.push_back(series(ero[i].first, rs, "ms_per_step", "drift_shown", i, false));
    }
    PlotSeries target;
    target.label = "target 100 M (two cores)";
    target.colour = cv::Scalar(40, 40, 40);
    target.dashed = true;
    target.x = {1, 2};
    target.y = {100, 100};
    rate.series.push_back(target);
    PlotSeries limit;
    limit.label = "target drift 1e-9";
    limit.colour = cv::Scalar(40, 40, 40);
    limit.dashed = true;
    double lo = 1e30, hi = 0;
    for (const auto& g : ero)
      for (const auto& r : g.second)
        lo = std::min(lo, jsonNumber(r, "ms_per_step")),
        hi = std::max(hi, jsonNumber(r, "ms_per_step"));
    limit.x = {lo, hi};
    limit.y = {1e-9, 1e-9};
    drift.series.push_back(limit);
    save({rate, drift}, "erosion.png");
  }
}

// track.png: time against tip error for each detector setting.
void trackingPlots(const std::vector<nlohmann::json>& records, const SavePlot& save) {
  const auto trk = groups(records, "track",
                          [](const auto& r) { return str(r, "detector") + " " + str(r, "scene"); });
  if (!trk.empty()) {
    PlotPanel med{"Tracking time vs tool tip error (median)",
                  "ms per frame",
                  "tip error median (mm)",
                  false,
                  false,
                  {}};
    PlotPanel p95{"Tracking time vs tool tip error (p95)",
                  "ms per frame",
                  "tip error p95 (mm)",
                  false,
                  false,
                  {}};
    for (std::size_t i = 0; i < trk.size(); ++i) {
      med.series.push_back(
          series(trk[i].first, trk[i].second, "ms", "tip_error_median_mm", i, false));
      p95.series.push_back(series(trk[i].first, trk[i].second, "ms", "tip_error_p95_mm", i, false));
    }
    save({med, p95}, "track.png");
  }
}

}  // namespace

double jsonNumber(const nlohmann::json& record, const char* key) {
  const auto it = record.find(key);
  return it != record.end() && it->is_number() ? it->get<double>() : std::nan("");
}

std::vector<std::filesystem::path> writeBenchPlots(const std::vector<nlohmann::json>& records,
                                                   const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> written;
  const SavePlot save = [&](const std::vector<PlotPanel>& panels, const char* name) {
    std::filesystem::create_directories(dir);
    io::writePngAtomically(drawPlots(panels), dir / name);
    written.push_back(dir / name);
  };
  for (const auto plot : {tessellationPlots, chartPlots, exportPlots, erosionPlots, trackingPlots})
    plot(records, save);
  return written;
}

}  // namespace ps::app
