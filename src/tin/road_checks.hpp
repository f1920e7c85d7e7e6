#pragma once
// What makes a road a proper mesh in its plane (the overlay's and the plane stitch's checks): no
// degenerate triangle, no two edges crossing, no two triangles overlapping.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "tin/overlay.hpp"
#include "tin/tin_locator.hpp"

namespace ps::tin {

double signedArea(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

// Each edge of the triangles once, as (smaller, larger) vertex.
std::set<std::pair<std::uint32_t, std::uint32_t>> edgesOf(
    const std::vector<std::array<std::uint32_t, 3>>& triangles);

// Throws core::InputError for a triangle naming a vertex the road lacks or with no area.
void refuseDegenerateTriangles(const Road& road);

// Throws core::InputError where two edges cross or two triangles overlap; `footprint` locates
// the road's triangles, `areaUnit` names the units of its coordinates' areas in the message.
void refuseSelfIntersection(const Road& road, const TinLocator& footprint,
                            const std::string& areaUnit = "lattice units^2");

}  // namespace ps::tin
