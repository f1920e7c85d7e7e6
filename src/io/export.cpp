#include "io/export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>

#include "core/chart_factory.hpp"
#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "io/heightmap_export.hpp"
#include "io/mesh_export.hpp"
#include "io/planet_file.hpp"
#include "io/tin_export.hpp"

namespace ps::io {

namespace {
// Aliases are the file extensions, so that the format follows from the output's name.
constexpr core::NameTable<ExportFormat, 9> kExportFormats{"export format",
                                                          {{{ExportFormat::kPng16, "png16"},
                                                            {ExportFormat::kTiff32, "tiff"},
                                                            {ExportFormat::kRaw32, "raw"},
                                                            {ExportFormat::kObj, "obj"},
                                                            {ExportFormat::kPly, "ply"},
                                                            {ExportFormat::kGlb, "glb"},
                                                            {ExportFormat::kPng16, "png"},
                                                            {ExportFormat::kTiff32, "tif"},
                                                            {ExportFormat::kRaw32, "f32"}}}};

}  // namespace

std::string toString(ExportFormat f) {
  return kExportFormats.nameOf(f);
}

ExportFormat exportFormatFromName(const std::string& name) {
  std::string s = name;
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return kExportFormats.parse(s);
}

ExportFormat exportFormatFromPath(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  if (ext.empty()) {
    throw core::InputError(path.string() +
                           ": no file extension to tell the format from; add one or pass --format");
  }
  try {
    return exportFormatFromName(ext.substr(1));
  } catch (const core::InputError&) {
    throw core::InputError(path.string() + ": unknown extension '" + ext +
                           "' (use .png .tif .tiff .raw .f32 .obj .ply .glb, or --format)");
  }
}

bool isMeshFormat(ExportFormat f) {
  return f == ExportFormat::kObj || f == ExportFormat::kPly || f == ExportFormat::kGlb;
}

nlohmann::json exportTerrain(const terrain::Terrain& t, const std::filesystem::path& out,
                             const ExportOptions& o) {
  const ExportFormat format = o.format ? *o.format : exportFormatFromPath(out);
  nlohmann::json summary = {{"file", out.string()},
                            {"format", toString(format)},
                            {"chart", t.chart().name()},
                            {"grid", t.grid().label()}};
  if (isMeshFormat(format)) {
    if (!o.maxErrorM) throw core::InputError("a mesh export needs --max-error METRES");
    if (o.width || o.height)
      throw core::InputError("--width/--height apply to heightmaps, not to meshes");
    const MeshExportReport r = exportMesh(t, *o.maxErrorM, meshFormatOf(format), out);
    summary["max_error_m"] = r.requestedErrorM;
    summary["meshed_at_error_m"] = r.meshedErrorM;
    summary["coordinate_rounding_m"] = r.roundingM;
    summary["vertices"] = r.vertices;
    summary["triangles"] = r.triangles;
    return summary;
  }
  if (o.maxErrorM)
    throw core::InputError("--max-error applies to meshes (obj, ply, glb), not to heightmaps");
  const core::ChartShape shape = core::shapeOf(t.chart());
  const bool flat = shape == core::ChartShape::kFlat;
  const bool tube = shape == core::ChartShape::kTorus || shape == core::ChartShape::kCylinder;
  int w = o.width, h = o.height;
  if (w < 0 || h < 0) throw core::InputError("--width and --height must be positive");
  const int m = t.grid().m();
  if (flat) {
    if (w == 0 && h == 0) w = h = m + 1;
    if (w == 0) w = h;
    if (h == 0) h = w;
  } else if (tube) {
    // The grid's own size: every vertex one pixel (a cylinder's ends both rows).
    const int rows = shape == core::ChartShape::kTorus ? m : m + 1;
    if (w == 0 && h == 0) w = m, h = rows;
    if (w == 0) w = std::max(1, int(std::lround(double(h) * m / rows)));
    if (h == 0) h = std::max(1, int(std::lround(double(w) * rows / m)));
  } else {
    if (w == 0 && h == 0) h = std::min(m, 8192);
    if (w == 0) w = 2 * h;
    if (h == 0) h = std::max(1, w / 2);
  }
  if (double(w) * h > 4e8 || w > 1 << 20 || h > 1 << 20) {
    throw core::InputError("heightmap size " + std::to_string(w) + "x" + std::to_string(h) +
                           " is too large");
  }
  const Raster raster = flat   ? resampleFlat(t, w, h, o.interpolation)
                        : tube ? resampleTube(t, w, h, o.interpolation)
                               : resampleEquirectangular(t, w, h, o.interpolation);
  switch (format) {
    case ExportFormat::kPng16:
      writeHeightPng16(raster, out);
      break;
    case ExportFormat::kTiff32:
      writeHeightTiff32(raster, out);
      break;
    default:
      writeHeightRaw32(raster, out);
      break;
  }
  summary["width"] = w;
  summary["height"] = h;
  summary["sidecar"] = out.string() + ".json";
  return summary;
}

bool isPlanetFile(const std::filesystem::path& path) {
  std::vector<unsigned char> head(8, 0);
  std::ifstream f(path, std::ios::binary);
  if (f) f.read(reinterpret_cast<char*>(head.data()), 8);
  head.resize(std::size_t(std::max<std::streamsize>(0, f.gcount())));
  return looksLikePlanetFile(head);
}

MeshFormat meshFormatOf(ExportFormat f) {
  return f == ExportFormat::kObj   ? MeshFormat::kObj
         : f == ExportFormat::kPly ? MeshFormat::kPly
                                   : MeshFormat::kGlb;
}

nlohmann::json exportTinFromFile(const std::filesystem::path& input,
                                 const ImportOptions& heightmapOptions,
                                 const std::filesystem::path& out, ExportFormat format,
                                 const TinExportOptions& options, std::vector<std::string>& notes) {
  if (!isMeshFormat(format))
    throw core::InputError("--tin writes a mesh (obj, ply, glb), not " + toString(format));
  nlohmann::json summary;
  if (isPlanetFile(input)) {
    const auto terrain = loadPlanet(input);
    summary = exportTerrainTin(*terrain, out, meshFormatOf(format), options);
    summary["chart"] = terrain->chart().name();
    summary["grid"] = terrain->grid().label();
  } else {
    if (heightmapOptions.gridSide > 0)
      throw core::InputError("--grid resamples; a TIN is meshed on the heightmap's own samples");
    HeightSamples samples = heightSamples(readHeightImage(input, heightmapOptions.encoding),
                                          heightmapOptions, input.string());
    notes = samples.notes;
    summary = exportSamplesTin(samples, out, meshFormatOf(format), options);
    summary["chart"] = "flat";
  }
  summary["file"] = out.string();
  summary["format"] = toString(format);
  return summary;
}

ExportInput loadExportInput(const std::filesystem::path& path,
                            const ImportOptions& heightmapOptions) {
  ExportInput in;
  if (isPlanetFile(path)) {
    in.terrain = loadPlanet(path);
    in.kind = "planet file";
    return in;
  }
  ImportResult r = importHeightmap(path, heightmapOptions);
  in.notes = std::move(r.notes);
  in.kind = "heightmap";
  try {
    // A heightmap is only exported here, never viewed: its radii would double the build.
    in.terrain =
        std::make_unique<terrain::Terrain>(r.planet.chart, std::move(r.planet.heights),
                                           r.planet.rule, terrain::BoundsContent::kErrorsOnly);
  } catch (const core::InputError& e) {
    throw core::InputError(path.string() + ": " + e.what());
  }
  return in;
}

}  // namespace ps::io
