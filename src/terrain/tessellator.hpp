#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "terrain/camera.hpp"
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::terrain {

struct TessellationSettings {
  double distMaxPx = 4.0;              // screen-space error bound (paper 003's best value)
  std::size_t triangleBudget = 70000;  // paper 003's budget; 0 means unlimited
  bool cull = true;                    // frustum and horizon culling
  bool operator==(const TessellationSettings&) const = default;
};

struct TessellationStats {
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  double effectiveDistMaxPx = 0;  // > distMaxPx when the budget bound and the view coarsened
  int passes = 0;                 // tessellation passes (more than one when the budget bound)
  bool coherentStart = false;     // began at the previous call's raised threshold
  bool reused = false;            // nothing changed: the previous mesh was returned untouched
  std::size_t visited = 0;        // bintree triangles examined in the last pass
  // Pairs of children emitted as leaves without a visit: their parent's ball and the largest
  // error among their split vertices proved that they do not split (last pass).
  std::size_t leafPairsUnvisited = 0;
  std::size_t culledFrustum = 0, culledHorizon = 0;
};

// View-dependent, crack-free tessellation of the 4-8 bintree. A triangle splits when its
// hypotenuse midpoint c has
//     f * eps(c) * min(kappa / (z(c) - r), (|c - eye| + r) / (z(c) - r)^2)  >  distMax,
// with r = radius(c) + eps(c): a bound on the screen distance between any full-resolution vertex
// in view inside c's diamond and the point the unsplit triangles put it at. The projection's
// Jacobian norm is f|X|/z^2 for X in the camera frame; over the ball of radius r around c,
// |X| <= |c - eye| + r and z >= z(c) - r, and over the image (grown by distMax) |X|/z <= kappa.
// Both bounds are nested, so a split
// vertex always has split parents and the mesh has no T-junctions, including across the seam
// (twins hold the same bounds) and at the poles. Balls outside the frustum or behind the
// planet's horizon are culled.
class Tessellator {
 public:
  // Throws core::InputError for a degenerate camera or non-positive/non-finite distMax.
  const Mesh& tessellate(const Terrain& terrain, const Camera& camera,
                         const TessellationSettings& settings);
  const TessellationStats& stats() const { return stats_; }
  const Mesh& mesh() const { return mesh_; }
  void invalidate() { cacheValid_ = false; }

 private:
  template <class ChartT>
  bool pass(const ChartT& chart, const Terrain& terrain, const Camera& camera, double distMax,
            bool cull, std::size_t abortAbove);
  std::uint32_t addVertex(std::uint64_t gridIndex, const Eigen::Vector3d& relativeToEye);
  // Mesh vertex of a split vertex of the current level, added on first use.
  std::uint32_t vertexFor(std::uint64_t gridIndex, const Eigen::Vector3d& relativeToEye);
  // Empties the vertex hash for a level where `nodes` triangles split (each adds one vertex at
  // most).
  void startLevelHash(std::size_t nodes);
  // Every triangle of levelNodes_ (level `depth` of the bintree): its split vertex's grid point,
  // height and bound codes into split_, in one tight loop of independent loads; true where the
  // level's lattice also gives the children's largest error.
  bool loadSplitVertices(const Terrain& terrain, int depth);
  std::size_t hashSlot(std::uint32_t key) const {
    return std::size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & hashMask_;
  }

  Mesh mesh_;
  TessellationStats stats_;
  // Grid coordinates fit 16 bits (m <= 2^15): a node takes 28 bytes instead of 40, and every
  // level's nodes are written once and read twice.
  struct Corner {
    std::uint16_t u, v;
  };
  struct Node {
    Corner a, b0, b1;
    std::uint32_t ia, ib0, ib1;  // mesh vertex indices of the corners
    std::uint8_t
        inside;  // bit i: ball inside frustum plane i; bit 5: in front of the horizon plane
  };
  std::vector<Node> levelNodes_, nextNodes_;  // one level of the bintree, and the next
  // The split vertices of levelNodes_, a quantity per array, so that their positions and split
  // decisions are computed for a whole level in loops the compiler vectorises.
  struct SplitVertices {
    std::vector<std::int32_t> u, v;
    std::vector<float> height;
    std::vector<std::uint16_t> error, radius, childError;  // bound codes (BoundCode)
    std::vector<double> x, y, z;         // the position, then the position relative to the eye
    std::vector<std::uint8_t> decision;  // SplitDecision
    void growTo(std::size_t n);          // grows only: no refills
  };
  SplitVertices split_;
  // Grid index -> mesh vertex, open addressing; a key and its value share a cache line. A split
  // vertex is asked for only by the two triangles of its diamond, which lie on the same level
  // of the bintree, so the table holds one level's vertices: sized to the level, it stays in
  // the L2 cache where one for the whole mesh did not.
  struct HashSlot {
    std::uint32_t key, value;
  };
  static constexpr std::uint32_t kEmpty = ~std::uint32_t(0);
  std::vector<HashSlot> hash_;  // the first hashMask_ + 1 slots are the current level's
  std::size_t hashMask_ = 0;

  // Frame coherence for the budget: the raised threshold the last call (with cachedSettings_)
  // settled on (0: the budget did not bind). The next call with the same settings starts there,
  // so a budget that binds frame after frame costs one pass instead of two or more.
  double budgetStart_ = 0;

  bool cacheValid_ = false;
  std::uint64_t cachedRevision_ = 0;
  Camera cachedCamera_;
  TessellationSettings cachedSettings_;
};

}  // namespace ps::terrain
