#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace ps::terrain {

// A tessellated view: unique vertices (grid index + position relative to the eye, so float
// keeps full precision near the camera) and CCW triangles (seen from outside the planet).
struct Mesh {
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();  // planet-frame origin of `positions`
  std::vector<std::uint64_t> gridIndex;           // per vertex: v * side + u
  std::vector<Eigen::Vector3f> positions;         // per vertex: P - eye
  std::vector<std::uint32_t> indices;             // 3 per triangle
  // Renewed every time the producer rebuilds this mesh in place, and unique across all meshes
  // of the process (nextMeshGeneration()): a renderer re-uploads only when it changed, and a
  // new mesh that happens to live where an old one did is not taken for it.
  std::uint64_t generation = 0;
  // A surface patch spliced in (terrain/mesh_patch: the sand TIN's region at its own detail):
  // vertices from patchVertexBegin on carry their own height (patchHeights) rather than their
  // grid vertex's, and triangles from index patchIndexBegin on are the patch's, which the
  // renderer shades from their own geometry (the grid under them holds the patch only at its
  // vertices). Empty patchHeights: no patch (every tessellator's mesh).
  std::size_t patchVertexBegin = 0, patchIndexBegin = 0;
  std::vector<float> patchHeights;

  std::size_t triangleCount() const { return indices.size() / 3; }
  void clear() {
    gridIndex.clear();
    positions.clear();
    indices.clear();
    patchHeights.clear();
    patchVertexBegin = patchIndexBegin = 0;
  }
};

// A value no mesh of this process has had as its generation yet.
std::uint64_t nextMeshGeneration();

}  // namespace ps::terrain
