// `planetsculpt bench tessellate`: view-dependent tessellation time against measured screen
// error, on the default planet, from orbit, 1,000 km and 1 km up, at 1280x720, on each chart of
// `--charts` (lat-long and octahedral by default: the same relief and grid, so the same memory;
// every row names its chart); then 1,000 km over the north pole and over the equator (rows
// `tessellate_chart`). `ms` is the median
// of repeated full tessellations of the same view by one tessellator (as frame after frame: a
// bound budget starts where the last call settled); `first_ms` / `first_passes` are the first,
// from a fresh tessellator. `host_memory_probe_ms` is a fixed memory workload timed just before
// the row (bench/host_probe.hpp): the host's slow phases show in it as well as in `ms`.
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/chart_option.hpp"
#include "bench/host_probe.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"

namespace ps::bench {

namespace {

struct View {
  std::string label;
  terrain::Camera camera;
};

// 1,000 km above the point of latitude `latDeg` on the 20 deg E meridian, looking 40 degrees
// below the horizon toward the north-north-east (toward 20 deg E + 180 over the pole).
View altitudeView(std::string label, double R, double latDeg) {
  const double lat = latDeg * std::numbers::pi / 180, lon = 20 * std::numbers::pi / 180;
  const Eigen::Vector3d up(std::cos(lon) * std::cos(lat), std::sin(lon) * std::cos(lat),
                           std::sin(lat));
  Eigen::Vector3d north(-std::cos(lon) * std::sin(lat), -std::sin(lon) * std::sin(lat),
                        std::cos(lat));
  const Eigen::Vector3d east = north.cross(up);
  const Eigen::Vector3d heading = (north + 0.3 * east).normalized();
  const Eigen::Vector3d eye = (R + 1.0e6) * up;
  return {std::move(label), terrain::Camera::lookAt(eye, eye + heading - 0.84 * up, up, 1280, 720,
                                                    60 * std::numbers::pi / 180)};
}

std::vector<View> standardViews(const terrain::Terrain& t) {
  const double R = t.chart().sphereRadius();
  // Over land at 30 deg N, 20 deg E looking east-north-east, so every view sees relief.
  const double lat = 30 * std::numbers::pi / 180, lon = 20 * std::numbers::pi / 180;
  const Eigen::Vector3d up(std::cos(lon) * std::cos(lat), std::sin(lon) * std::cos(lat),
                           std::sin(lat));
  const Eigen::Vector3d east = Eigen::Vector3d(-std::sin(lon), std::cos(lon), 0);
  const Eigen::Vector3d north = up.cross(east);
  const Eigen::Vector3d heading = (east + 0.3 * north).normalized();
  const double fov = 60 * std::numbers::pi / 180;
  std::vector<View> views;
  views.push_back({"orbit_3R", terrain::Camera::lookAt(3 * R * up, Eigen::Vector3d::Zero(), north,
                                                       1280, 720, fov)});
  {
    const Eigen::Vector3d eye = (R + 1.0e6) * up;
    views.push_back({"altitude_1000km",
                     terrain::Camera::lookAt(eye, eye + heading - 0.8 * up, up, 1280, 720, fov)});
  }
  {
    // 1 km above the ground under the camera.
    const auto uv = *t.chart().inverse(up);
    const double ground = t.height(int(std::lround(uv.x())), int(std::lround(uv.y())));
    const Eigen::Vector3d eye = (R + std::max(0.0, ground) + 1000.0) * up;
    views.push_back({"altitude_1km",
                     terrain::Camera::lookAt(eye, eye + heading - 0.15 * up, up, 1280, 720, fov)});
  }
  return views;
}

}  // namespace

// The standard views on one chart's planet: its memory row, then one row per view, dist_max and
// budget.
void benchTessellateOn(core::ChartShape shape, const BenchOptions& options, std::ostream& out) {
  const int level = options.quick ? 11 : 13;
  const double rssBefore = procStatusMiB("VmRSS");
  double buildS = 0;
  std::unique_ptr<terrain::Terrain> planet;
  buildS = timeMs([&] { planet = app::makeDefaultPlanet(level, 1, shape); }) / 1000.0;
  const double rssAfter = procStatusMiB("VmRSS");
  const std::string chart = planet->chart().name();
  out << nlohmann::json{{"bench", "tessellate_memory"},
                        {"chart", chart},
                        {"grid", planet->grid().label()},
                        {"planet_mib", double(planet->bytes()) / (1 << 20)},
                        {"bytes_per_vertex",
                         double(planet->bytes()) / double(planet->grid().count())},
                        {"rss_delta_mib", rssAfter - rssBefore},
                        {"rss_mib", rssAfter},
                        {"generate_and_build_s", buildS}}
             .dump()
      << std::endl;

  const std::vector<double> sweep = options.quick
                                        ? std::vector<double>{1, 4, 16}
                                        : std::vector<double>{0.1, 0.25, 0.5, 1, 2, 4, 8, 16};
  HostMemoryProbe probe;
  for (const View& view : standardViews(*planet)) {
    for (const double distMax : sweep) {
      for (const std::size_t budget : {std::size_t(70000), std::size_t(0)}) {
        if (budget == 0 && distMax < 2 && view.label != "orbit_3R")
          continue;  // unbudgeted fine views are huge
        // Below 0.5 px only the orbit view: the default relief is smooth, and from orbit these
        // are the settings whose meshes reach the 70,000-triangle budget.
        if (distMax < 0.5 && view.label != "orbit_3R") continue;
        terrain::TessellationSettings s;
        s.distMaxPx = distMax;
        s.triangleBudget = budget;
        terrain::Tessellator tess;
        std::vector<double> full, cached;
        int firstPasses = 0;
        const double probeMs = probe.medianMs();
        for (int r = 0; r < options.repeats; ++r) {
          tess.invalidate();
          full.push_back(timeMs([&] { tess.tessellate(*planet, view.camera, s); }));
          if (r == 0) firstPasses = tess.stats().passes;
          cached.push_back(timeMs([&] { tess.tessellate(*planet, view.camera, s); }));
        }
        const auto st = tess.stats();
        const auto err = terrain::measureScreenError(*planet, view.camera, tess.mesh());
        const double fullMs = median(full), cachedMs = median(cached);
        out << nlohmann::json{{"bench", "tessellate"},
                              {"chart", chart},
                              {"grid", planet->grid().label()},
                              {"view", view.label},
                              {"width", 1280},
                              {"height", 720},
                              {"dist_max", distMax},
                              {"budget", budget},
                              {"effective_dist_max", st.effectiveDistMaxPx},
                              {"passes", st.passes},
                              // A fresh tessellator: no earlier call to start a bound budget from.
                              {"first_ms", full.front()},
                              {"first_passes", firstPasses},
                              {"triangles", st.triangles},
                              {"ms", fullMs},
                              {"ms_p90", percentile(full, 0.9)},
                              {"host_memory_probe_ms", probeMs},
                              {"ms_over_probe", fullMs / probeMs},
                              {"unchanged_view_ms", cachedMs},
                              {"unchanged_over_full", cachedMs / fullMs},
                              {"max_screen_error_px", err.maxPx},
                              {"vertices_checked", err.verticesChecked},
                              {"culled_frustum", st.culledFrustum},
                              {"culled_horizon", st.culledHorizon},
                              {"rule", terrain::toString(planet->bounds().rule())}}
                   .dump()
            << std::endl;
      }
    }
  }
}

// The same relief (terrain/relief: a function of the direction) on both sphere charts at the
// same grid: triangles and time against the measured screen error, over a pole (lat-long's
// crowded rows; on the octahedral chart an ordinary place) and over the equator.
void benchTessellateCharts(const BenchOptions& options, const ChartChoice& charts,
                           std::ostream& out) {
  const int level = options.quick ? 11 : 13;
  const std::vector<double> sweep =
      options.quick ? std::vector<double>{1, 4} : std::vector<double>{0.5, 1, 2, 4, 8};
  for (const core::ChartShape shape : charts.shapes()) {
    const auto planet = app::makeDefaultPlanet(level, 1, shape);
    const double R = planet->chart().sphereRadius();
    for (const View& view :
         {altitudeView("pole_1000km", R, 89.0), altitudeView("equator_1000km", R, 0.0)}) {
      for (const double distMax : sweep) {
        terrain::TessellationSettings s;
        s.distMaxPx = distMax;
        s.triangleBudget = 0;  // the mesh the error asks for, however large
        terrain::Tessellator tess;
        std::vector<double> full;
        for (int r = 0; r < options.repeats; ++r) {
          tess.invalidate();
          full.push_back(timeMs([&] { tess.tessellate(*planet, view.camera, s); }));
        }
        const auto st = tess.stats();
        const auto err = terrain::measureScreenError(*planet, view.camera, tess.mesh());
        out << nlohmann::json{{"bench", "tessellate_chart"},
                              {"chart", planet->chart().name()},
                              {"grid", planet->grid().label()},
                              {"bytes", planet->bytes()},
                              {"view", view.label},
                              {"dist_max", distMax},
                              {"triangles", st.triangles},
                              {"ms", median(full)},
                              {"max_screen_error_px", err.maxPx},
                              {"vertices_checked", err.verticesChecked}}
                   .dump()
            << std::endl;
      }
    }
  }
}

void benchTessellate(const BenchOptions& options, const ChartChoice& charts, std::ostream& out) {
  for (const core::ChartShape shape : charts.shapes()) benchTessellateOn(shape, options, out);
  benchTessellateCharts(options, charts, out);
}

static const BenchRegistration kTessellate(
    "tessellate", "View-dependent tessellation time against measured screen error",
    [](CLI::App& command) -> BenchFunction {
      auto charts = std::make_shared<ChartChoice>();
      addChartsOption(command, *charts);
      return
          [charts](const BenchOptions& o, std::ostream& out) { benchTessellate(o, *charts, out); };
    });

}  // namespace ps::bench
