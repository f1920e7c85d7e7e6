#pragma once
// `planetsculpt export ... --tin`: a planet or a flat heightmap as a triangulated irregular
// network (src/tin) in OBJ, PLY or GLB, with its error measured on every sample of the file as
// written (coordinates rounded as the format stores them).
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "io/heightmap_import.hpp"
#include "io/mesh_export.hpp"
#include "terrain/terrain.hpp"
#include "tin/sample_field.hpp"

namespace ps::io {

struct TinExportOptions {
  double maxErrorM = 0;  // everywhere the control map is black (or everywhere, without one)
  // A grey image of the lattice's own size (a heightmap's W x H; a planet's grid side^2): its
  // white pixels allow controlErrorM, black ones maxErrorM, grey ones in between (linearly).
  std::optional<std::filesystem::path> controlMap = {};
  std::optional<double> controlErrorM = {};
  double minAngleDeg = 0;  // 0: fewest triangles (greedy); else the quality refinement
  double minAreaM2 = 0;    // triangles smaller than this are not split for their angle
  // Planets: mesh only the grid's window covering south, west, north, east (degrees; west <
  // east, the seam not crossed); the control map then matches the window's samples.
  std::optional<std::array<double, 4>> regionDeg = {};
};

// The samples a TIN of this terrain is measured on: the 3D distance on a sphere's chart, the
// vertical one on a flat chart (the field refers to the terrain's heights: keep it alive).
tin::SampleField terrainSampleField(const terrain::Terrain& terrain);
// A flat heightmap's own samples, vertical distance (refers to samples.heights).
tin::SampleField heightSampleField(const HeightSamples& samples);

// A planet (3D distance on its chart; the mesh welded at the seam and poles) or a flat terrain
// from a planet file (vertical distance).
nlohmann::json exportTerrainTin(const terrain::Terrain& terrain, const std::filesystem::path& out,
                                MeshFormat format, const TinExportOptions& options);

// A flat heightmap's own W x H samples (vertical distance; x = column * dx, y = rows counted
// from the bottom * dy, z = the height).
nlohmann::json exportSamplesTin(const HeightSamples& samples, const std::filesystem::path& out,
                                MeshFormat format, const TinExportOptions& options);

}  // namespace ps::io
