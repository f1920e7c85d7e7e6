// `planetsculpt bench sand-tin-charts`: the TIN sand tool's same stamp on every chart (issue 43):
// lat-long, octahedral, torus and cylinder, each on sand of one depth, at a plain place and
// across a pole, a fold or a seam. One row per chart and place: the stamp's time through the edit
// pipeline (median of `repeats`, each stamp undone before the next, so every stamp makes its
// region TIN from the same heights), the region's grid points and TIN vertices, the volume the
// stamp moved and the grid's volume drift, and the time as a ratio to lat-long's plain place in
// the same run.
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "core/chart_factory.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/sand_grid.hpp"
#include "sand/tin_sand_tool.hpp"
#include "terrain/terrain.hpp"

namespace ps::bench {
namespace {

constexpr double kDepth = 2000.0;  // m of sand before each stamp
constexpr double kPress = 1500.0;  // m the tool's lowest point lies under the sand's surface

struct Place {
  const char* name;
  double u, v;  // fractions of m
};

struct ChartCase {
  core::ChartShape shape;
  std::vector<Place> places;
};

std::vector<ChartCase> cases() {
  using S = core::ChartShape;
  return {{S::kLatLong, {{"plain", 0.3, 0.5}, {"seam", 0.0, 0.5}, {"pole", 0.0, 1.0}}},
          {S::kOctahedral,
           {{"plain", 0.3, 0.4},
            {"fold", 0.0, 0.3},
            {"south pole", 0.0, 0.0},
            {"north pole", 0.5, 0.5}}},
          {S::kTorus, {{"plain", 0.3, 0.3}, {"seams' crossing", 0.0, 0.0}}},
          {S::kCylinder, {{"plain", 0.3, 0.5}, {"seam", 0.0, 0.5}}}};
}

void benchSandTinCharts(const BenchOptions& options, std::ostream& out) {
  const int side = options.quick ? 1025 : 2049;  // 100 km stamps need cells under 50 km
  const int repeats = options.quick ? 3 : std::max(3, options.repeats / 3);
  const core::GridSize grid = core::GridSize::fromSide(side);
  sand::TinSandToolSettings settings;  // the tool's defaults: 100 km stamps, regions of 5 radii
  double reference = 0;
  for (const ChartCase& c : cases()) {
    const auto chart = core::makeChart(c.shape, grid, app::resolveDims(c.shape, {}));
    terrain::Terrain t(chart, std::vector<float>(grid.count(), float(kDepth)));
    edit::EditPipeline pipe(t);
    const sand::TinSandTool tool(chart, settings);
    const sand::SandGrid cells(chart);
    for (const Place& place : c.places) {
      const core::GridPoint at{int(std::lround(place.u * grid.m())),
                               int(std::lround(place.v * grid.m()))};
      const Eigen::Vector3d tip = chart->position(at.u, at.v, 0.0) +
                                  (kDepth - kPress + settings.radius) * chart->up(at.u, at.v);
      std::vector<double> ms;
      double drift = 0;
      for (int k = 0; k < repeats; ++k) {
        const double before = cells.volume(t.heights());
        ms.push_back(timeMs([&] { pipe.apply(tool, {tip, 0.0}); }));
        drift = std::max(
            drift, std::abs(cells.volume(t.heights()) - before) / cells.absVolume(t.heights()));
        if (k + 1 < repeats) pipe.undo();
      }
      const sand::TinSandToolStats& s = tool.lastStats();
      pipe.undo();
      const double med = median(ms);
      if (reference == 0) reference = med;
      const nlohmann::json row = {{"bench", "sand-tin-charts"},
                                  {"chart", chart->name()},
                                  {"place", place.name},
                                  {"grid", side},
                                  {"radius_m", settings.radius},
                                  {"region_m", tool.regionMetres(*chart)},
                                  {"grid_points", s.gridVertices},
                                  {"tin_vertices", s.tinVertices},
                                  {"changed", s.changed},
                                  {"displaced_m3", s.displacedVolume},
                                  {"volume_drift", drift},
                                  {"ms", med},
                                  {"ratio_to_latlong_plain", med / reference},
                                  {"repeats", repeats}};
      out << row.dump() << std::endl;
      std::cerr << "bench sand-tin-charts: " << chart->name() << " " << place.name << " " << med
                << " ms\n";
    }
  }
}

}  // namespace

static const BenchRegistration kSandTinCharts(
    "sand-tin-charts", "the TIN sand tool's same stamp on every chart: time, points, volume",
    benchSandTinCharts);

}  // namespace ps::bench
