// `planetsculpt overlay TERRAIN ROAD.obj --mode stitch|stencil --error E --out FILE`: a road
// (any triangle mesh: a road, a path) stitched or stenciled into the terrain's TIN (paper 001).
#include <iostream>
#include <memory>
#include <sstream>

#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "io/overlay_export.hpp"

namespace ps::app {

namespace {

struct OverlayArgs {
  std::string terrain, road, output, mode = "stitch", at, format, encoding = "stored",
                                     stitchIn = "plane";
  std::optional<double> error, spacing, scale, offset;
};

// "A,B" or "A,B,C" -> three numbers (the third 0 when absent).
std::array<double, 3> parseAt(const std::string& s) {
  std::array<double, 3> v{0, 0, 0};
  std::stringstream in(s);
  std::string item;
  int n = 0;
  while (std::getline(in, item, ',')) {
    if (n == 3) throw core::InputError("--at '" + s + "': at most three numbers");
    std::size_t used = 0;
    try {
      v[std::size_t(n)] = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v[std::size_t(n)]))
      throw core::InputError("--at '" + s + "': '" + item + "' is not a number");
    ++n;
  }
  if (n < 2) throw core::InputError("--at '" + s + "': give LAT,LON[,HEADING] (or X,Y[,HEADING])");
  return v;
}

int runOverlay(const OverlayArgs& a) {
  io::OverlayOptions o;
  if (a.mode == "stitch") {
    o.mode = tin::OverlayMode::kStitch;
  } else if (a.mode == "stencil") {
    o.mode = tin::OverlayMode::kStencil;
  } else {
    throw core::InputError("--mode '" + a.mode + "' is not one of stitch, stencil");
  }
  if (a.stitchIn != "plane" && a.stitchIn != "grid")
    throw core::InputError("--stitch-in '" + a.stitchIn + "' is not one of plane, grid");
  o.stitchInGrid = a.stitchIn == "grid";
  if (!a.error) throw core::InputError("overlay needs --error METRES (the terrain TIN's error)");
  o.errorM = *a.error;
  if (!a.at.empty()) o.at = parseAt(a.at);
  io::ImportOptions heightmap;
  heightmap.chart = io::ChartKind::kFlat;
  heightmap.spacing = a.spacing;
  heightmap.scale = a.scale;
  heightmap.offset = a.offset;
  heightmap.encoding = io::pngHeightEncodingFromString(a.encoding);
  const io::ExportFormat format =
      a.format.empty() ? io::exportFormatFromPath(a.output) : io::exportFormatFromName(a.format);
  std::vector<std::string> notes;
  const nlohmann::json summary =
      io::overlayFromFiles(a.terrain, heightmap, a.road, a.output, format, o, notes);
  for (const auto& note : notes) std::cerr << "overlay: " << a.terrain << ": " << note << "\n";
  std::cout << summary.dump() << "\n";
  return 0;
}

const CommandRegistration kOverlay([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<OverlayArgs>();
  sub = root.add_subcommand("overlay",
                            "Stitch or stencil a road (a triangle mesh OBJ) into a terrain's TIN");
  sub->add_option("terrain", a->terrain,
                  "Planet file, a heightmap (its own samples), or a flat terrain mesh (.obj, as "
                  "`export --tin` writes for a heightmap: kept as it is)")
      ->required();
  sub->add_option("road", a->road,
                  "Road mesh (OBJ triangles): x, y metres in its own frame, z height above the "
                  "terrain's datum (stencil keeps it; stitch takes the terrain's)")
      ->required();
  sub->add_option("--out", a->output, "Output mesh (.obj with groups terrain and road, .ply, .glb)")
      ->required();
  sub->add_option("--mode", a->mode,
                  "stitch (every edge of both kept, split where they cross, heights from the "
                  "terrain; on a sphere in the road's own plane, its edges exact) or stencil (the "
                  "road's geometry kept, the terrain re-meshed around it)")
      ->capture_default_str();
  sub->add_option(
      "--error", a->error,
      "The terrain TIN's largest error in metres (the stencil keeps it around the road; on a "
      "planet a road laid in the grid has its edges halved until none strays further from its "
      "path)");
  sub->add_option("--at", a->at,
                  "Where the road's origin lies and the heading of its +y axis (degrees clockwise "
                  "from north): on a sphere LAT,LON[,HEADING]; on a torus AROUND,ACROSS[,HEADING] "
                  "(degrees round the big circle and round the tube from its outer equator); on a "
                  "cylinder AROUND,ALONG[,HEADING] (degrees round the axis, metres along it from "
                  "the middle); on a flat terrain X,Y[,HEADING] in metres (default 0,0,0)");
  sub->add_option("--stitch-in", a->stitchIn,
                  "On a sphere: plane (the road's own, seen from the centre: its edges exact) or "
                  "grid (the chart's, as before 2026-12-08; for comparison)")
      ->capture_default_str();
  sub->add_option("--format", a->format, "obj | ply | glb (overrides the extension)");
  sub->add_option("--spacing", a->spacing,
                  "Heightmap terrain: metres between pixels; mesh terrain: the step it is sampled "
                  "at for the stencil (default: its smallest vertex gap)");
  sub->add_option("--scale", a->scale, "Heightmap terrain: metres = value * scale + offset");
  sub->add_option("--offset", a->offset, "Heightmap terrain: metres = value * scale + offset");
  sub->add_option("--encoding", a->encoding,
                  "Heightmap terrain: stored (grey PNG) | terrain-rgb | terrarium")
      ->capture_default_str();
  return [a] { return runOverlay(*a); };
});

}  // namespace
}  // namespace ps::app
