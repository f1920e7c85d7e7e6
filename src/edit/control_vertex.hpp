#pragma once
#include <Eigen/Core>
#include <string>

#include "core/chart.hpp"
#include "core/grid.hpp"

namespace ps::edit {

// The control vertex of an edit (paper 003, section 6.1): the grid vertex nearest to a point p of
// the planet frame (the tool tip), by 3D distance between p and the vertices' positions on the
// reference sphere (height 0). On a sphere that is the vertex whose direction is closest to p's
// direction, whatever p's altitude: the vertex "under" the tool, independent of the sculpted
// heights (a cliff next to the tool cannot steal the control vertex, and the choice agrees with
// the deformation area, which is measured on the sphere too).
//
// Found without scanning the planet: chart.inverse(p) gives fractional (u, v), then a local
// search over rows round(v) - 2 .. round(v) + 2 and, in each, the columns next to round(u) (the
// nearest vertex of a latitude row is the one of nearest longitude; rows further than 1.5 cells
// can never win). The seam wraps, a pole row is one point (returned as u = 0) and a seam vertex
// is returned as u = 0; a torus's rows wrap too (row m is returned as row 0). Ties go to the
// first candidate in (v, u) order.
//
// Throws core::InputError naming the position when p is not finite or lies at the planet's
// centre (no direction).
core::GridPoint nearestVertex(const core::Chart& chart, const Eigen::Vector3d& p);

// The quantity nearestVertex() maximises (tests compare it with a scan of every vertex): on the
// lat-long chart direction(u, v) . p, on other charts -|position(u, v, 0) - p|^2.
double nearness(const core::Chart& chart, int u, int v, const Eigen::Vector3d& p);

// "(x, y, z) m" with full precision, for messages.
std::string describePoint(const Eigen::Vector3d& p);

}  // namespace ps::edit
