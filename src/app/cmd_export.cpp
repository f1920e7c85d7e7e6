// `planetsculpt export INPUT --out FILE`: a planet file (or a heightmap, taken as a flat terrain)
// -> 16-bit PNG, float TIFF, raw float32 + sidecar, or a mesh (OBJ, binary PLY, GLB) at a
// view-independent maximum error.
#include <iostream>
#include <memory>

#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "io/export.hpp"
#include "io/tin_export.hpp"

namespace ps::app {

namespace {

struct ExportArgs {
  std::string input, output, format, noData = "fill", noDataValue, interpolation = "cubic",
                                     encoding = "stored";
  bool tin = false;
  std::string controlMap;
  std::optional<double> controlError;
  double minAngle = 0, minArea = 0;
  std::vector<double> region;
  int width = 0, height = 0;
  std::optional<double> maxError, scale, offset, spacing;
  long long grid = 0;
};

int runExport(const ExportArgs& a) {
  io::ImportOptions heightmap;
  heightmap.chart = io::ChartKind::kFlat;
  heightmap.scale = a.scale;
  heightmap.offset = a.offset;
  heightmap.spacing = a.spacing;
  heightmap.gridSide = a.grid;
  heightmap.interpolation = io::interpolationFromString(a.interpolation);
  heightmap.encoding = io::pngHeightEncodingFromString(a.encoding);
  heightmap.noData = io::noDataPolicyFromString(a.noData);
  if (!a.noDataValue.empty()) {
    heightmap.noDataValue = io::noDataValueFromString(a.noDataValue);
  }
  io::ExportOptions o;
  if (!a.format.empty()) o.format = io::exportFormatFromName(a.format);
  o.width = a.width;
  o.height = a.height;
  o.maxErrorM = a.maxError;
  o.interpolation = heightmap.interpolation;
  // Check the output side before the (possibly long) load.
  const io::ExportFormat format = o.format ? *o.format : io::exportFormatFromPath(a.output);
  if (a.tin) {
    if (!o.maxErrorM) throw core::InputError("--tin needs --max-error METRES");
    io::TinExportOptions t;
    t.maxErrorM = *o.maxErrorM;
    if (!a.controlMap.empty()) t.controlMap = a.controlMap;
    t.controlErrorM = a.controlError;
    t.minAngleDeg = a.minAngle;
    t.minAreaM2 = a.minArea;
    if (!a.region.empty()) {
      if (a.region.size() != 4)
        throw core::InputError("--region takes SOUTH,WEST,NORTH,EAST (four numbers, degrees)");
      t.regionDeg = std::array<double, 4>{a.region[0], a.region[1], a.region[2], a.region[3]};
    }
    std::vector<std::string> notes;
    const nlohmann::json summary =
        io::exportTinFromFile(a.input, heightmap, a.output, format, t, notes);
    for (const auto& note : notes) std::cerr << "export: " << a.input << ": " << note << "\n";
    std::cout << summary.dump() << "\n";
    return 0;
  }
  if (!a.controlMap.empty() || a.controlError || a.minAngle != 0 || a.minArea != 0)
    throw core::InputError(
        "--control-map, --control-error, --min-angle and --min-area are TIN "
        "settings: add --tin");
  if (io::isMeshFormat(format) && !o.maxErrorM)
    throw core::InputError("a mesh export needs --max-error METRES");

  io::ExportInput in = io::loadExportInput(a.input, heightmap);
  for (const auto& note : in.notes) std::cerr << "export: " << a.input << ": " << note << "\n";
  const nlohmann::json summary = io::exportTerrain(*in.terrain, a.output, o);
  std::cout << summary.dump() << "\n";
  return 0;
}

const CommandRegistration kExport([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<ExportArgs>();
  sub = root.add_subcommand(
      "export", "Export a planet (or a heightmap as a flat terrain) as a heightmap or a mesh");
  sub->add_option("input", a->input,
                  "Planet file, or a heightmap (PNG, TIFF, raw + sidecar) meshed as a flat terrain")
      ->required();
  sub->add_option("--out", a->output,
                  "Output file; the format follows the extension (.png .tif .raw .obj .ply .glb)")
      ->required();
  sub->add_option("--format", a->format,
                  "png16 | tiff | raw | obj | ply | glb (overrides the extension)");
  sub->add_option("--width", a->width,
                  "Heightmap width in pixels (default: the grid's resolution)");
  sub->add_option("--height", a->height, "Heightmap height in pixels");
  sub->add_option("--interpolation", a->interpolation,
                  "Resampling between the grid and pixels: cubic (Catmull-Rom) or bilinear")
      ->capture_default_str();
  sub->add_option(
      "--max-error", a->maxError,
      "Meshes: the largest distance in metres between the mesh and any full-resolution vertex");
  sub->add_flag("--tin", a->tin,
                "Mesh as a triangulated irregular network (Delaunay; paper 001) instead of the "
                "bintree: fewest triangles, or with --min-angle a quality mesh");
  sub->add_option("--control-map", a->controlMap,
                  "TIN: grey image the size of the samples; white pixels get --control-error, "
                  "black ones --max-error, grey in between");
  sub->add_option("--control-error", a->controlError,
                  "TIN: the largest error in metres where the control map is white");
  sub->add_option("--min-angle", a->minAngle,
                  "TIN: smallest triangle angle in degrees (0: fewest triangles; proven to end up "
                  "to 20.7, tried up to 34 within a budget and reported)")
      ->capture_default_str();
  sub->add_option("--min-area", a->minArea,
                  "TIN: triangles below this many square metres are not split for their angle")
      ->capture_default_str();
  sub->add_option("--region", a->region,
                  "TIN of a planet: only SOUTH,WEST,NORTH,EAST (degrees; not across +-180)")
      ->delimiter(',')
      ->expected(4);
  sub->add_option("--encoding", a->encoding,
                  "Heightmap input: PNG heights as stored (grey), or a web DEM tile's "
                  "terrain-rgb (Mapbox) or terrarium packing")
      ->capture_default_str();
  sub->add_option("--spacing", a->spacing,
                  "Heightmap input: metres between pixels (default: from the file, else 1)");
  sub->add_option("--scale", a->scale, "Heightmap input: metres = value * scale + offset");
  sub->add_option("--offset", a->offset, "Heightmap input: metres = value * scale + offset");
  sub->add_option("--grid", a->grid,
                  "Heightmap input: grid side 2^n+1 (default: the smallest holding every pixel)");
  sub->add_option("--nodata", a->noData, "Heightmap input: fill or refuse no-data pixels")
      ->capture_default_str();
  sub->add_option("--nodata-value", a->noDataValue,
                  "Heightmap input: declare the no-data value (number or nan)");
  return [a] { return runExport(*a); };
});

}  // namespace
}  // namespace ps::app
