#pragma once
// A road over or near one of lat-long's poles (docs/CHARTS.md, "Roads over lat-long's poles"):
// there a whole grid row is one point and the grid's columns meet, so the road gets a vertex at
// the pole, is parted from it to its border (round the pole the grid is a strip whose ends the
// seam glues), laid round it by longitude without winding, its triangles near the pole halved
// until none is large for its distance from it, and the pole's vertex spread along the pole's
// row under each of its neighbours. Used by io/road_placement.cpp.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/chart.hpp"
#include "io/road_placement.hpp"
#include "io/road_unfolding.hpp"
#include "tin/overlay.hpp"

namespace ps::io {

// A road in its own plane (x, y; z its height) and its triangles.
struct RoadMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// Lat-long's poles that face the road's plane: each one's point in the plane and its grid row.
std::vector<std::pair<Eigen::Vector2d, double>> polesInPlane(const core::Chart& chart, double m,
                                                             const RoadFrame& frame);

// The road's vertex at each pole its footprint holds (or lies within `snap` of), and its grid
// row; `slits` gets each one's parting end (-1: none needed). Throws core::InputError, prefixed
// with `name`, for a road whose pole no edge joins to its border.
std::vector<std::pair<std::uint32_t, double>> insertPoles(RoadMesh& mesh, const core::Chart& chart,
                                                          double m, const RoadFrame& frame,
                                                          double snap,
                                                          std::vector<std::int64_t>& slits,
                                                          const std::string& name);

// The triangles not round a pole whose longest edge, longer than `shortest`, is above `widest`
// times their distance from a pole (`at`): those to halve.
std::vector<std::size_t> wideNearPoles(const RoadMesh& mesh,
                                       const std::vector<std::pair<Eigen::Vector2d, double>>& at,
                                       const std::vector<std::pair<std::uint32_t, double>>& poles,
                                       double shortest, double widest);

// Each grid vertex's u set by its longitude, taken on from the parting at `end` through a turn.
void unwrapRoundPole(tin::Road& grid, const std::vector<Eigen::Vector3d>& onSurface,
                     const std::vector<std::array<std::uint32_t, 3>>& triangles, std::uint32_t end,
                     double m);

// The pole's vertex spread along its grid row (copies under each neighbour, fillers between).
struct PoleFan {
  std::vector<std::array<std::uint32_t, 3>> own;
  std::vector<std::uint32_t> origin;
  std::vector<char> poleCopy;
};
PoleFan spreadPoles(tin::Road& grid, std::vector<Eigen::Vector3d>& onSurface,
                    const std::vector<std::array<std::uint32_t, 3>>& triangles,
                    const std::vector<std::pair<std::uint32_t, double>>& poles);

// An edge from a pole's copy runs in the grid from the pole's row to its other end, on the
// sphere a spiral out of the pole where the road's edge is straight: it lies inside the road's
// fan about the pole either way (no terrain left under the road or taken from beside it), and
// halving it would not shorten its stray, so its stray is set to 0 (and `strayM` taken again).
void leavePoleEdgesUnjudged(UnfoldedRoad& unfolded, const tin::Road& grid, const PoleFan& fan);

// Marks for halving (`strays` of every edge but those from a pole set infinite) the triangles
// near a pole that are large for their distance from it (wideNearPoles, an eighth) and, where
// the grid still turns one over (`turned`), it and the triangles round its corners. Returns
// whether it marked any.
bool markNearPoles(const RoadMesh& mesh, const std::vector<std::pair<Eigen::Vector2d, double>>& at,
                   const std::vector<std::pair<std::uint32_t, double>>& poles,
                   const std::vector<std::size_t>& turned, double shortest,
                   std::vector<std::array<double, 3>>& strays);

}  // namespace ps::io
