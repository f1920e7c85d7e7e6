// `bench export`'s planet overlay rows (tool planet-overlay): a 300 x 10 km road stitched into
// Mars (the shared MOLA grid) on both sphere charts, in the road's own plane (the default,
// tin/plane_stitch) and in the chart's grid (`overlay --stitch-in grid`, tin/overlay), the same
// road at the same places in one run, through `overlay`'s own path (io::overlayFromFiles: the
// planet read, its TIN built, the road stitched, the mesh written). Per row: the whole call's
// time, the road group's triangles, its edges' stray, crossings, the added vertices' distance
// from the terrain mesh and the topology; each grid row also its time over the plane's. Over the
// pole only the plane's row: the grid refuses that stitch.
#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "app/build_paths.hpp"
#include "bench/bench_export.hpp"
#include "bench/bench_util.hpp"
#include "io/heightmap_import.hpp"
#include "io/overlay_export.hpp"
#include "io/planet_file.hpp"

namespace ps::bench {

void benchExportPlanetOverlay(bool quick, const std::filesystem::path& work, std::ostream& out) {
  namespace fs = std::filesystem;
  const fs::path mars = ps::app::sharedDir() / "data" / "dem" / "mars_mola_1440x720_u16.png";
  if (!fs::exists(mars)) {
    std::cerr << "bench export: " << mars.string() << " is absent; the planet overlay is skipped\n";
    return;
  }
  const fs::path road = work / "overlay_road.obj";
  std::ofstream(road) << "v -150000 -5000 0\nv 150000 -5000 0\nv 150000 5000 0\n"
                         "v -150000 5000 0\nf 1 2 3\nf 1 3 4\n";
  const double error = quick ? 200.0 : 50.0;
  for (const io::ChartKind chart : {io::ChartKind::kOctahedral, io::ChartKind::kLatLong}) {
    io::ImportOptions o;
    o.chart = chart;
    o.radius = 3389500.0;
    o.offset = -32768.0;
    o.westLongitudeDeg = 0.0;
    o.gridSide = quick ? 257 : 1025;
    const io::ImportResult imported = io::importHeightmap(mars, o);
    const fs::path planet = work / "overlay_mars.planet";
    io::savePlanet(*imported.planet.chart, imported.planet.heights, imported.planet.rule, planet);
    for (const std::array<double, 3> at :
         {std::array<double, 3>{30, 45, 20}, std::array<double, 3>{-60, 90, 70},
          std::array<double, 3>{90, 0, 0}}) {
      double planeMs = 0;
      for (const bool inGrid : {false, true}) {
        io::OverlayOptions options;
        options.errorM = error;
        options.at = at;
        options.stitchInGrid = inGrid;
        const bool overPole = chart == io::ChartKind::kLatLong && at[0] == 90;
        if (inGrid && overPole) continue;
        std::vector<std::string> notes;
        nlohmann::json s;
        const double ms = timeMs([&] {
          s = io::overlayFromFiles(planet, io::ImportOptions{}, road, work / "overlay_out.obj",
                                   io::ExportFormat::kObj, options, notes);
        });
        if (!inGrid) planeMs = ms;
        nlohmann::json line = {{"bench", "export"},
                               {"tool", "planet-overlay"},
                               {"planet", "mars-mola"},
                               {"chart", imported.planet.chart->name()},
                               {"grid", imported.planet.chart->grid().label()},
                               {"at", at},
                               {"error_m", error},
                               {"stitch_in", inGrid ? "grid" : "plane"},
                               {"stitched_in", s["stitched_in"]},
                               {"ms", ms},
                               {"road_group_triangles", s["road_group_triangles"]},
                               {"road_stray_m", s["road_stray_m"]},
                               {"crossing_vertices", s["crossing_vertices"]},
                               {"added_vertex_error_m", s["added_vertex_error_m"]},
                               {"terrain_tin_vertices", s["terrain_tin_vertices"]},
                               {"euler", s["euler"]},
                               {"border_edges", s["border_edges"]},
                               {"non_manifold_edges", s["non_manifold_edges"]}};
        if (inGrid) line["time_ratio_to_plane"] = ms / planeMs;
        out << line.dump() << std::endl;
      }
    }
  }
}

}  // namespace ps::bench
