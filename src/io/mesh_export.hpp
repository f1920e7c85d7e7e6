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

// Unit normal per mesh vertex: the area-weighted sum of its triangles' normals, with seam twins
// and each pole row counted as one vertex, so shading is continuous across the seam.
std::vector<Eigen::Vector3f> vertexNormals(const terrain::Terrain& terrain,
                                           const terrain::Mesh& mesh);

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
// `meshOut`, when given, receives the mesh that was written.
MeshExportReport exportMesh(const terrain::Terrain& terrain, double maxErrorM, MeshFormat format,
                            const std::filesystem::path& path, terrain::Mesh* meshOut = nullptr);

}  // namespace ps::io
