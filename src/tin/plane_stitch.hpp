#pragma once
// A road stitched into a closed surface mesh in the road's own plane, not in a chart's grid.
//
// Seen from a centre the surface is star-shaped about (a planet's), the surface's flat triangles
// project onto the road's plane as straight-edged triangles (a central projection maps a plane
// triangle's edges to lines), tiling it once where the surface faces the centre. There the
// road's edges and the terrain's are inserted into one constrained triangulation, every terrain
// edge kept, and each new vertex (a road corner, a crossing) is lifted back along its ray onto
// the terrain triangle it lies in: the surface is unchanged, and each road edge runs along the
// plane through the centre and its two ends (on a sphere its great circle), as the grid's drape
// lays it (tin/road_drape.hpp). Nothing depends on the chart: this is how a road is stitched over
// one of lat-long's poles, where a grid row is one point and the grid's stitch cannot tell the
// crossings there apart (docs/CHARTS.md).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "core/input_error.hpp"

namespace ps::tin {

struct SurfaceMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// The road's plane: `origin` on it, `up` its unit normal pointing away from `centre`, `x` and
// `y` orthonormal axes in it with x cross y = up. A road point (a, b) is origin + a x + b y.
struct RoadPlane {
  Eigen::Vector3d centre, origin, up, x, y;
};

struct PlaneStitch {
  SurfaceMesh mesh;  // the surface's vertices first, same indices, then the added ones
  std::vector<std::uint8_t> onRoad;  // per triangle: inside the road's footprint
  std::size_t regionTriangles = 0;   // the surface's triangles meshed again about the road
  std::size_t roadVertices = 0;      // added where a road vertex lies (not on a terrain vertex)
  std::size_t crossingVertices = 0;  // added where a road edge crosses a terrain edge
  double addedVertexErrorM = 0;      // largest distance of an added vertex from its triangle
};

// Thrown where the surface about the road is not seen one to one in its plane: a triangle there
// seen edge-on or from behind (where a chart's grid folds, a triangle of its TIN may have three
// corners on one great circle), two vertices on one ray, or triangles reaching too far round. A
// caller may stitch in a chart's grid instead.
class SurfaceUnseenInPlane : public core::InputError {
 public:
  using core::InputError::InputError;
};

// Throws core::InputError for a road that is not a proper mesh in its plane (degenerate or
// overlapping triangles, crossing edges) or too large for it (the surface about it must face
// the centre within 60 degrees), and SurfaceUnseenInPlane (above).
PlaneStitch stitchInPlane(const SurfaceMesh& surface, const RoadPlane& plane,
                          const std::vector<Eigen::Vector2d>& roadXY,
                          const std::vector<std::array<std::uint32_t, 3>>& roadTriangles);

}  // namespace ps::tin
