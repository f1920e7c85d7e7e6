#pragma once
// A triangulated irregular network from a sampled surface (paper 001's terrain mesh): every
// sample ends within its allowed error of the TIN, measured on every sample.
//
//   fewest triangles (minAngleDeg = 0): greedy insertion (Garland and Heckbert's; Delatin's):
//     the sample with the largest error relative to its tolerance is inserted into the Delaunay
//     triangulation until none exceeds it; only the triangles around each new vertex are
//     measured again. Then each vertex whose removal keeps every sample of the re-filled hole
//     within its tolerance is removed (one sweep in rows; about 10-19 % fewer triangles for
//     about a third more time, docs/BENCHMARKS.md).
//   quality (minAngleDeg > 0): the greedy TIN, its border constrained, then Delaunay
//     refinement (CGAL's Delaunay_mesher_2) with a criterion that splits a triangle whose
//     smallest angle is under the request (unless smaller than minArea) or whose error exceeds
//     the tolerance on any sample it covers. Up to kGuaranteedAngleDeg the refinement provably
//     ends; above it, it runs within a budget of new vertices, and when the budget runs out the
//     angle criterion is dropped and only the error is refined (so the error always holds) and
//     the angle reached is reported.
//
// On a planet (ErrorMetric::kChart3d) the lattice is the chart's grid: seam twins are inserted
// together, so both sides of the seam carry the same vertices and the welded mesh is closed.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "tin/sample_field.hpp"

namespace ps::tin {

// Ruppert / Shewchuk: Delaunay refinement terminates for angle bounds up to arcsin(1 / (2 sqrt
// 2)) = 20.7 degrees (CGAL's Delaunay_mesh_criteria_2 documents the same bound, B = 0.125).
inline constexpr double kGuaranteedAngleDeg = 20.7;
// Requests above this are refused: Delaunay refinement is not known to end there at all.
inline constexpr double kMaxAngleDeg = 34.0;

struct TinOptions {
  double minAngleDeg = 0;  // 0: fewest triangles; else in (0, kMaxAngleDeg]
  double minArea = 0;      // lattice units^2: triangles smaller than this are not split for angle
  // Steiner points the angle refinement may add above kGuaranteedAngleDeg; 0: 4x the greedy
  // TIN's vertex count + 10,000.
  std::size_t steinerBudget = 0;
  // After greedy insertion, remove the vertices the error does not need (fewer triangles for
  // some more time; off: the plain greedy TIN, as Delatin makes it).
  bool removeRedundant = true;
};

struct Tin {
  std::vector<Eigen::Vector2d> xy;                      // vertices, lattice coordinates
  std::vector<double> h;                                // their heights (metres)
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise in (x, y)
};

struct TinReport {
  std::size_t greedyVertices = 0;   // after greedy insertion (and removal)
  std::size_t removedVertices = 0;  // by the redundant-vertex pass
  std::size_t steinerVertices = 0;  // added by the quality refinement
  std::size_t vertices = 0, triangles = 0;
  double requestedAngleDeg = 0;
  double smallestAngleDeg = 0;   // over every triangle of the result
  bool angleMet = true;          // smallestAngleDeg >= request (within 1e-6 degrees)
  bool budgetExhausted = false;  // the angle refinement stopped at its budget
  double greedyMs = 0, removeMs = 0, refineMs = 0;
};

// Throws core::InputError for a field that does not validate or options out of range.
Tin buildTin(const SampleField& field, const TinOptions& options, TinReport* report = nullptr);

}  // namespace ps::tin
