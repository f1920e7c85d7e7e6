#pragma once
// A road on a planet across the glued sides of its chart's grid (docs/EXPORT.md, "overlay"). The
// plane around the grid continues it as the chart glues its sides: beyond a seam the grid again,
// shifted by its side m; beyond a fold (each side of the octahedral chart glued to itself,
// mirrored at its midpoint) the grid turned half round that midpoint. A road laid on the sphere
// is unfolded into that plane, one piece, and each part of it is then moved back into the grid by
// the gluing that brings it there: a road across lat-long's seam or an octahedral fold becomes
// pieces that meet at the side, twin to twin.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/chart.hpp"
#include "tin/overlay.hpp"

namespace ps::io {

// x -> s x + t: one of the plane's moves that the chart's gluing makes (s = -1: a half turn).
struct PlaneMove {
  double s = 1;
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  Eigen::Vector2d operator()(const Eigen::Vector2d& x) const { return s * x + t; }
  bool operator==(const PlaneMove&) const = default;
};

// The identity, each side's gluing and their products up to `depth` of them (depth 3 reaches
// every copy of the grid next to it, through a side or a corner), each once.
std::vector<PlaneMove> gluingMoves(const core::Chart& chart, double m, int depth = 3);

// A point of the plane around the grid moved back into [0, m]^2 by the sides' gluing (open
// sides and pole rows clamp, or with `clampOpen` false leave it beyond them).
Eigen::Vector2d intoGrid(const core::Chart& chart, double m, Eigen::Vector2d p,
                         bool clampOpen = true);

// The planes through the sphere's centre (unit normals, each once) of the chart's glued sides
// that are great-circle arcs: lat-long's seam, the octahedral folds (southern half-meridians).
std::vector<Eigen::Vector3d> gluedSidePlanes(const core::Chart& chart, double m);

// A road in its own frame (x, y; z its height) with its triangles cut where `f`, affine in x and
// y, changes sign: each piece on one side of the line f = 0, the cut points on it (f = 0 there,
// one vertex for both triangles of a cut edge).
void cutRoadAlong(std::vector<Eigen::Vector3d>& vertices,
                  std::vector<std::array<std::uint32_t, 3>>& triangles,
                  const std::function<double(const Eigen::Vector3d&)>& f);

// `road.xy` holds each vertex's grid point (the chart's inverse of `onSurface`, the vertex on the
// surface); `midpoint(a, b)` is the surface's point halfway along the edge from vertex a to b (the
// road's own path, which a straight grid edge is judged against). Returns the road unfolded and
// moved back into the grid, one copy of its vertices and triangles for each gluing that brings some
// of it into [0, m]^2 (the overlay clips each copy at the grid's border); a vertex a copy brings
// home (within 1e-9 of the grid's side of its own grid point) gets that point's exact bits, so
// copies weld where they meet. Throws core::InputError, prefixed with `name`, for a road that
// cannot be unfolded in one piece (one around an end of a fold, where the grid has a corner of 180
// degrees), naming the place. With `unfoldedAlready`, `road.xy` is taken as the road unfolded
// (a road round lat-long's pole, io/road_placement.cpp's unwrapRoundPole).
struct UnfoldedRoad {
  tin::Road road;
  int pieces = 0;     // copies laid: 1 + one for each glued side the road crosses into
  double strayM = 0;  // the largest distance of an edge's grid midpoint, on the surface, from
                      // the edge's own midpoint: how far a straight grid edge strays
  std::vector<std::array<double, 3>> edgeStrayM;  // each triangle's edges (k to k + 1), alike
};
UnfoldedRoad unfoldRoad(
    const tin::Road& road, const std::vector<Eigen::Vector3d>& onSurface,
    const std::function<Eigen::Vector3d(std::uint32_t, std::uint32_t)>& midpoint,
    const core::Chart& chart, double m, const std::string& name, bool unfoldedAlready = false);

}  // namespace ps::io
