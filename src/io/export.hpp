#pragma once
// `planetsculpt export`: a planet (or a heightmap taken as a flat terrain) -> heightmap or mesh.
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/heightmap_import.hpp"
#include "terrain/terrain.hpp"

namespace ps::io {

enum class ExportFormat { kPng16, kTiff32, kRaw32, kObj, kPly, kGlb };

std::string toString(ExportFormat f);
// "png16"/"png", "tiff"/"tif", "raw"/"f32", "obj", "ply", "glb"; throws core::InputError.
ExportFormat exportFormatFromName(const std::string& name);
// From the file name's extension (.png .tif .tiff .raw .f32 .obj .ply .glb).
ExportFormat exportFormatFromPath(const std::filesystem::path& path);
bool isMeshFormat(ExportFormat f);
// True when the file starts with a planet file's magic (anything else is taken as a heightmap).
bool isPlanetFile(const std::filesystem::path& path);

struct ExportOptions {
  std::optional<ExportFormat> format;                   // unset: from the extension
  int width = 0, height = 0;                            // heightmaps; 0: the default size
  std::optional<double> maxErrorM;                      // meshes (required for them)
  Interpolation interpolation = Interpolation::kCubic;  // heightmaps: sampling the grid
};

// Writes `out` (and a sidecar JSON for heightmaps); returns a summary of what was written.
nlohmann::json exportTerrain(const terrain::Terrain& terrain, const std::filesystem::path& out,
                             const ExportOptions& options);

// The input of `export`: a planet file, or any heightmap `import` reads, which becomes a flat
// terrain (heightmapOptions.chart decides; its notes are what the user must be told).
struct ExportInput {
  std::unique_ptr<terrain::Terrain> terrain;
  std::string kind;  // "planet file" | "heightmap"
  std::vector<std::string> notes;
};
ExportInput loadExportInput(const std::filesystem::path& path,
                            const ImportOptions& heightmapOptions);

// `export --tin`: a planet file (its grid; 3D error on a sphere) or a heightmap's own samples
// (nothing resampled; vertical error) as a TIN in a mesh format. `notes` receives what the user
// must be told about the input.
struct TinExportOptions;
enum class MeshFormat;
MeshFormat meshFormatOf(ExportFormat f);  // obj, ply, glb
nlohmann::json exportTinFromFile(const std::filesystem::path& input,
                                 const ImportOptions& heightmapOptions,
                                 const std::filesystem::path& out, ExportFormat format,
                                 const TinExportOptions& options, std::vector<std::string>& notes);

}  // namespace ps::io
