#pragma once
// Triangle meshes to files, whatever made them (the bintree export, the TIN export): positions
// in metres, counter-clockwise triangles, optional per-vertex normals. Every writer is atomic.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ps::io {

struct MeshData {
  std::vector<Eigen::Vector3d> positions;  // metres
  std::vector<Eigen::Vector3f> normals;    // unit, one per position (PLY and GLB; empty: computed)
  std::vector<std::uint32_t> indices;      // three per triangle
  std::string description;                 // OBJ's and PLY's comment line
  // OBJ only: a group per triangle (index into groupNames), written as `g NAME` sections in
  // group order. Empty: one unnamed group.
  std::vector<std::uint8_t> triangleGroup;
  std::vector<std::string> groupNames;
};

// Area-weighted vertex normals of a welded mesh (a vertex without area gets +z).
std::vector<Eigen::Vector3f> areaWeightedNormals(const MeshData& mesh);

// Wavefront OBJ, "%.4f" coordinates.
void writeObjFile(const MeshData& mesh, const std::filesystem::path& path);
// Binary little-endian PLY: float x y z nx ny nz per vertex, int triangles.
void writePlyFile(const MeshData& mesh, const std::filesystem::path& path);
// Binary glTF 2.0: float POSITION and NORMAL, uint32 indices. glTF is +Y up: (x, y, z) is
// written as (x, z, -y), a rotation, so winding and handedness are kept. `extrasJson` goes into
// the asset's extras.
void writeGlbFile(const MeshData& mesh, const std::filesystem::path& path,
                  const std::string& extrasJson = "{}");

}  // namespace ps::io
