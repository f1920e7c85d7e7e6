// `planetsculpt bench charts`: how evenly each chart spends its samples on the sphere (issue 28's
// choice of the octahedral mapping). For lat-long, the octahedral chart's equal-area mapping
// and its central projection, at 8193^2 (--quick: 1025^2): the largest and smallest cell area
// (each cell's area on the unit sphere from 2 x 2 chord quadrilaterals, so that a cell a crease
// crosses is measured bent; lat-long's pole cells are triangles), their ratio, and the largest
// and smallest spacing between neighbouring grid vertices (a pole row's zero-length steps left
// out), with the largest spacing against lat-long's in the same run.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include <filesystem>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "app/default_planet.hpp"
#include "app/snapshot.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "io/heightmap_export.hpp"
#include "terrain/tessellator.hpp"

namespace ps::bench {

namespace {

struct ChartStats {
  double areaMin = INFINITY, areaMax = 0, spacingMin = INFINITY, spacingMax = 0;
};

ChartStats measure(const core::Chart& chart) {
  const int m = chart.grid().m();
  ChartStats total;
#pragma omp parallel
  {
    ChartStats s;
    // Rows of positions at half steps: row 2v, 2v + 1 and 2v + 2 of the half grid.
    std::vector<Eigen::Vector3d> rows[3];
    for (auto& r : rows) r.resize(std::size_t(2 * m + 1));
#pragma omp for schedule(dynamic, 16)
    for (int v = 0; v < m; ++v) {
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i <= 2 * m; ++i)
          rows[k][std::size_t(i)] = chart.positionAt(0.5 * i, v + 0.5 * k, 0);
      for (int u = 0; u < m; ++u) {
        double area = 0;
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) {
            const std::size_t c = std::size_t(2 * u + i);
            const Eigen::Vector3d &a = rows[j][c], &b = rows[j][c + 1], &d = rows[j + 1][c],
                                  &e = rows[j + 1][c + 1];
            area += 0.5 * (e - a).cross(d - b).norm();
          }
        s.areaMin = std::min(s.areaMin, area);
        s.areaMax = std::max(s.areaMax, area);
        // The cell's bottom and left edges between grid vertices (top and right are the next
        // cells'; the last row and column are measured by the cells below and left of them).
        const std::size_t c = std::size_t(2 * u);
        for (const double len :
             {(rows[0][c + 2] - rows[0][c]).norm(), (rows[2][c] - rows[0][c]).norm()}) {
          if (len > 1e-12) s.spacingMin = std::min(s.spacingMin, len);
          s.spacingMax = std::max(s.spacingMax, len);
        }
      }
    }
#pragma omp critical
    {
      total.areaMin = std::min(total.areaMin, s.areaMin);
      total.areaMax = std::max(total.areaMax, s.areaMax);
      total.spacingMin = std::min(total.spacingMin, s.spacingMin);
      total.spacingMax = std::max(total.spacingMax, s.spacingMax);
    }
  }
  return total;
}

// The two sphere charts' grids side by side (--out DIR: DIR/charts_grids.png): the same relief on
// a 33^2 grid of each, every grid edge drawn, seen from 50 degrees N so that the north pole and
// the equator are both in view. Lat-long's rows close into the pole; the octahedral grid's cells
// keep one size, its creases (the octahedron's edges) showing as lines where the cells turn.
void writeGridPictures(const std::string& dir) {
  cv::Mat panels;
  for (const core::ChartShape shape : {core::ChartShape::kLatLong, core::ChartShape::kOctahedral}) {
    const auto planet = app::makeDefaultPlanet(5, 1, shape);
    const double R = planet->chart().sphereRadius(), lat = 50 * std::numbers::pi / 180;
    const Eigen::Vector3d eye = 4.0 * R * Eigen::Vector3d(std::cos(lat), 0.0, std::sin(lat));
    const auto camera = terrain::Camera::lookAt(eye, Eigen::Vector3d::Zero(),
                                                Eigen::Vector3d::UnitZ(), 640, 640, 0.6);
    terrain::Tessellator tess;
    terrain::TessellationSettings s;
    s.distMaxPx = 1e-6;  // every grid vertex
    s.triangleBudget = 0;
    cv::Mat img = app::renderSnapshot(*planet, tess.tessellate(*planet, camera, s), camera, true);
    cv::putText(img, planet->chart().name() + " " + planet->grid().label(), {16, 36},
                cv::FONT_HERSHEY_SIMPLEX, 0.9, cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
    if (panels.empty()) {
      panels = img;
    } else {
      cv::hconcat(panels, img, panels);
    }
  }
  std::filesystem::create_directories(dir);
  io::writePngAtomically(panels, std::filesystem::path(dir) / "charts_grids.png");
}

}  // namespace

void benchCharts(const BenchOptions& o, std::ostream& out) {
  if (!o.outDir.empty()) writeGridPictures(o.outDir);
  const int n = o.quick ? 10 : 13;
  const core::GridSize g(n);
  const double R = 6372790.0;
  std::vector<std::unique_ptr<core::Chart>> charts;
  charts.push_back(std::make_unique<core::LatLongChart>(g, 1.0));
  charts.push_back(std::make_unique<core::OctahedralChart>(g, 1.0));
  charts.push_back(
      std::make_unique<core::OctahedralChart>(g, 1.0, core::OctahedralChart::Mapping::kCentral));
  double latLongSpacingMax = 0;
  for (const auto& chart : charts) {
    std::cerr << "bench charts: " << chart->name() << " " << g.label() << "\n";
    double ms = 0;
    ChartStats s;
    ms = timeMs([&] { s = measure(*chart); });
    if (chart->name() == "latlong") latLongSpacingMax = s.spacingMax;
    out << nlohmann::json{{"bench", "charts"},
                          {"chart", chart->name()},
                          {"grid", g.label()},
                          {"cell_area_max_over_min", s.areaMax / s.areaMin},
                          {"cell_area_min_km2", s.areaMin * R * R * 1e-6},
                          {"cell_area_max_km2", s.areaMax * R * R * 1e-6},
                          {"spacing_min_m", s.spacingMin * R},
                          {"spacing_max_m", s.spacingMax * R},
                          {"spacing_max_over_latlong",
                           latLongSpacingMax > 0 ? s.spacingMax / latLongSpacingMax : 0.0},
                          {"ms", ms}}
               .dump()
        << std::endl;
  }
}

namespace {
const BenchRegistration kCharts("charts", "How evenly each chart spends its samples on the sphere",
                                benchCharts);
}  // namespace

}  // namespace ps::bench
