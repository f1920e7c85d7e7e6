#pragma once
// A road laid on a planet's surface (docs/EXPORT.md, "overlay"): its plane tangent at the place
// `--at` names, taken onto the surface by each point's nearest surface point (on a sphere,
// through the centre: the gnomonic projection), cut where it crosses a glued side of the chart's
// grid (io/road_unfolding.hpp), and its edges halved until, straight in the grid, they follow
// the surface's paths within a tolerance.
#include <Eigen/Core>
#include <array>
#include <string>

#include "core/chart.hpp"
#include "io/obj_triangles.hpp"
#include "tin/overlay.hpp"

namespace ps::io {

struct LaidRoad {
  tin::Road road;          // grid coordinates, one copy per piece (the overlay clips each at the
                           // grid's border; a cylinder's road may reach past its rims)
  int pieces = 1;          // the copies: 1 + one per glued side the road crosses into
  double strayM = 0;       // the largest distance of a laid edge's grid midpoint from its own
  int halvedEdges = 0;     // edges halved so that none strays beyond the tolerance
  bool holdsPole = false;  // its footprint holds one of lat-long's poles (a vertex there)
};

// The road's plane at a place: its origin on the surface, the surface's outward normal there,
// and the road's x and y axes in the tangent plane (y at the heading, x 90 degrees clockwise).
struct RoadFrame {
  Eigen::Vector3d origin, up, x, y;
  Eigen::Vector3d at(const Eigen::Vector3d& p) const { return origin + p.x() * x + p.y() * y; }
};
// `at` as layRoadOnPlanet's below. Throws core::InputError for a place off the surface or a
// chart with no places (a flat one), naming `name`.
RoadFrame roadFrame(const core::Chart& chart, const std::array<double, 3>& at,
                    const std::string& name);

// The place of a point on the surface (`at` without its heading): the inverse of roadFrame's
// origin. Throws core::InputError for a flat chart.
std::array<double, 2> placeOf(const core::Chart& chart, const Eigen::Vector3d& p);

// The surface's outward unit normal at the surface point nearest to p (heights displace along it).
Eigen::Vector3d surfaceNormal(const core::Chart& chart, const Eigen::Vector3d& p);

// `at`: on a sphere LAT, LON (degrees); on a torus AROUND, ACROSS (degrees round the big circle
// from +x and round the tube from its outer equator); on a cylinder AROUND (degrees from +x) and
// ALONG (metres along the axis from the tube's middle); then the heading of the road's +y axis,
// degrees clockwise from north (the direction of growing latitude, ACROSS or ALONG) seen from
// outside. Edges are halved until every edge's stray is at most `toleranceM` (or shorter than
// 1e-5 of the road's extent). Throws core::InputError,
// prefixed with `name`, for a place off the surface, a road around the end of an octahedral fold,
// and one that folds over in the grid (larger than its place on a tube allows, or turned over
// near lat-long's pole, where the grid's columns meet). A road over one of lat-long's poles gets a
// vertex there, spread along the pole's grid row (docs/CHARTS.md).
LaidRoad layRoadOnPlanet(const ObjTriangles& road, const core::Chart& chart, double m,
                         const std::array<double, 3>& at, double toleranceM,
                         const std::string& name);

}  // namespace ps::io
