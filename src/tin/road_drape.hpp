#pragma once
// A road stitched onto a planet's terrain TIN, draped over the mesh instead of laid in the grid.
//
// The terrain TIN's triangles are flat in space and span many grid cells where the ground is
// plain; a grid point inside one is put on the mesh at the triangle's blend of its corners, which
// is not over the chart's point for that grid point: near the poles such a road vertex slid up to
// 1.7 km along the surface (docs/EXPORT.md). Draped, each road vertex goes where the surface's
// normal through its chart point meets the mesh, and each road edge follows the mesh along the
// plane through its two draped ends that holds the surface's normal at its middle (on a sphere
// the plane through the centre: the great circle the road was laid along). Within one terrain
// triangle that path is straight in the grid too (the triangle is affine in both), so an edge
// becomes a polyline whose inner points lie on the terrain edges it crosses, exactly: at dyadic
// fractions of an edge between integer lattice points, which the triangulation's exact
// predicates then see on the edge, not beside it.
//
// Vertices on the lattice's border stay where they are (a glued side's twins must stay twins),
// and so do edges along the border.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "tin/sample_field.hpp"
#include "tin/tin_locator.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::tin {

struct Road;

struct DrapedRoad {
  std::vector<Eigen::Vector2d> vertex;  // each road vertex's lattice point on the mesh
  // Each road edge (a < b) as the points between its two ends, from a towards b (empty: straight).
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<Eigen::Vector2d>> inner;
  std::size_t drapedEdges = 0;
  std::size_t straightEdges = 0;  // the walk over the mesh failed (left a border): kept straight
  double largestMoveM = 0;        // the farthest a road vertex's mesh point moved along the mesh
  // The points of road edge (a, b) from a to b, both ends included.
  std::vector<Eigen::Vector2d> path(std::uint32_t a, std::uint32_t b) const;
};

// Every road vertex and edge draped over `terrain` (lattice coordinates of `field`, a planet's:
// ErrorMetric::kChart3d; every terrain vertex on a lattice point). `corner` holds the terrain
// vertices' positions, `onTerrain` locates its triangles.
DrapedRoad drapeRoad(const SampleField& field, const Tin& terrain,
                     const std::vector<Eigen::Vector3d>& corner, const TinLocator& onTerrain,
                     const Road& road);

// Whether a terrain can be draped on: a planet's field and a TIN whose vertices all lie on
// lattice points (what buildTin makes without Steiner points).
bool drapeable(const SampleField& field, const Tin& terrain);

// The road's footprint as its draped triangles (polygons whose sides are the draped edges):
// whether one of them holds a point (even-odd, so a point on a side may go either way). A face of
// a triangulation that has every draped side as a constraint is inside or out by its centroid,
// which lies on no side.
class DrapedFootprint {
 public:
  DrapedFootprint(const DrapedRoad& drape, const std::vector<std::array<std::uint32_t, 3>>& tris,
                  double width, double height);
  bool contains(const Eigen::Vector2d& p) const;

 private:
  std::vector<std::vector<Eigen::Vector2d>> polygon_;
  double bucket_ = 8.0;
  int bw_ = 1, bh_ = 1;
  std::vector<std::vector<std::uint32_t>> buckets_;
};

}  // namespace ps::tin
