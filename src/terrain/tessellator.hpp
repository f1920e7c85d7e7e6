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
  bool reused = false;            // nothing changed: the previous mesh was returned untouched
  std::size_t visited = 0;        // bintree triangles examined in the last pass
  std::size_t culledFrustum = 0, culledHorizon = 0;
};

// View-dependent, crack-free tessellation of the 4-8 bintree. A triangle splits when its
// hypotenuse midpoint c has
//     f * eps(c) * (|c - eye| + r) / (z(c) - r)^2  >  distMax,   r = radius(c) + eps(c),
// a bound on the screen distance between any full-resolution vertex in c's diamond and the
// point the unsplit triangles put it at (the projection's Jacobian norm is f|X|/z^2 for X in the
// camera frame; X ranges over the ball of radius r around c). Both bounds are nested, so a split
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
  void buildVertices(const Terrain& terrain, const Camera& camera);

  Mesh mesh_;
  TessellationStats stats_;
  std::vector<std::uint64_t> triangleCorners_;  // 3 grid indices per emitted triangle
  std::vector<std::uint64_t> hashKeys_;
  std::vector<std::uint32_t> hashValues_;

  bool cacheValid_ = false;
  std::uint64_t cachedRevision_ = 0;
  Camera cachedCamera_;
  TessellationSettings cachedSettings_;
};

}  // namespace ps::terrain
