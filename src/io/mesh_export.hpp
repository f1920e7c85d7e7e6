#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "io/mesh_writers.hpp"
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::io {

// Wavefront OBJ of a tessellated mesh, positions in metres in the planet frame (recomputed in
// double from the grid, not from the eye-relative floats). Atomic.
void writeObj(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
              const std::filesystem::path& path);

// A tessellated mesh welded by the chart's topology, as every mesh file is written: the grid
// vertices at one surface point (core::Chart::canonical: the seam's twins, a pole row) are one
// vertex (its canonical grid index), and triangles that weld to a segment (two vertices of a
// pole row) are dropped, so a whole planet is a closed 2-manifold (each edge in two triangles,
// Euler characteristic 2).
terrain::Mesh weldMesh(const terrain::Terrain& terrain, const terrain::Mesh& mesh);

// weldMesh's result for the writers: positions in metres, planet frame, recomputed in double
// from the grid; `withNormals`: unit, area-weighted, one per vertex.
MeshData weldedMeshData(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
                        bool withNormals, std::string description);

// Binary little-endian PLY: float x y z nx ny nz per vertex (metres, planet frame, z up) and
// int triangles. Atomic.
void writePly(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
              const std::filesystem::path& path);

// Binary glTF 2.0 (.glb): one triangle mesh with float POSITION (metres) and NORMAL and
// uint32 indices. glTF is +Y up: a planet-frame point (x, y, z) is written as (x, z, -y), a
// rotation, so winding and handedness are kept. `extras` goes into the asset's extras. Atomic.
void writeGlb(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
              const std::filesystem::path& path, const std::string& extrasJson = "{}");

enum class MeshFormat { kObj, kPly, kGlb };
std::string toString(MeshFormat f);

// A mesh from any mesher (io/mesh_writers.hpp) in `format`; `extrasJson` goes into a GLB's
// asset extras. Atomic.
void writeMeshFile(const MeshData& mesh, MeshFormat format, const std::filesystem::path& path,
                   const std::string& extrasJson = "{}");

// The largest distance the format's coordinate rounding (float32; OBJ's 4 decimals) can move
// any vertex of this terrain, from a bound on the coordinates' magnitude.
double coordinateRoundingBound(const terrain::Terrain& terrain, MeshFormat format);

struct MeshExportReport {
  double requestedErrorM = 0;  // what the user asked for
  double roundingM = 0;        // coordinateRoundingBound
  double meshedErrorM = 0;     // what meshToError was given: requested - rounding
  std::size_t vertices = 0, triangles = 0;
};

// The whole planet meshed to a view-independent maximum error and written in `format`: the
// mesh is built by terrain::meshToError at (maxErrorM - rounding), so that after the format
// rounds the coordinates every full-resolution vertex still lies within maxErrorM of the
// written surface. Throws core::InputError when maxErrorM is not above the rounding.
// `meshOut`, when given, receives the mesh before welding (weldMesh of it is what was written;
// the report counts the welded vertices and triangles).
MeshExportReport exportMesh(const terrain::Terrain& terrain, double maxErrorM, MeshFormat format,
                            const std::filesystem::path& path, terrain::Mesh* meshOut = nullptr);

}  // namespace ps::io
