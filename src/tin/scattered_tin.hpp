#pragma once
// An error-bounded TIN of scattered points in a plane (a planet region's grid points seen in
// the tangent plane at its centre: the sand TIN tool's region), made with the TIN export's
// generation (tin/tin_mesher: greedy insertion and redundant-vertex removal) and then checked
// at every point:
//
//   1. the Delaunay TIN of every point (the surface the grid's points span);
//   2. that surface sampled on a square lattice of `spacing` over the points' bounding box (a
//      sample outside their hull takes the surface's height where the line to the box's centre
//      enters it) and meshed by buildTin to `tolerance` (vertical error);
//   3. the points' convex hull and those lattice vertices that lie half a spacing or more inside
//      it start a DynamicTin (its domain is the points' hull, as the all-points TIN's);
//   4. every point is measured against it, and the points over tolerance are inserted at their
//      own heights, the worst first, until none is: so every point ends within `tolerance` of
//      the TIN (step 2's guarantee holds on the lattice, and a re-triangulation of cocircular
//      lattice points may choose other diagonals: step 4 makes the bound hold at the points).
#include <Eigen/Core>
#include <span>

#include "tin/dynamic_tin.hpp"

namespace ps::tin {

struct ScatteredTinReport {
  std::size_t points = 0;           // the input points
  std::size_t latticeSamples = 0;   // step 2's lattice
  std::size_t latticeVertices = 0;  // buildTin's TIN of it
  std::size_t hullVertices = 0;     // step 3's hull
  std::size_t startVertices = 0;    // step 3's DynamicTin
  std::size_t repaired = 0;         // points inserted in step 4
  int repairRounds = 0;
  std::size_t vertices = 0;  // at the end
  double maxError = 0;       // m: the largest |point height - TIN height| at the end
};

// Throws core::InputError for fewer than three non-collinear points, a spacing or tolerance
// that is not positive and finite, or a lattice of over 2^26 samples.
DynamicTin errorBoundedTin(std::span<const Eigen::Vector3d> points, double spacing,
                           double tolerance, ScatteredTinReport* report = nullptr);

// The convex hull's corners (indices into xy), counter-clockwise, collinear points left out
// (Andrew's monotone chain).
std::vector<std::size_t> convexHull(std::span<const Eigen::Vector3d> points);

}  // namespace ps::tin
