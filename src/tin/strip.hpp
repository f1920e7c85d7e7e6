#pragma once
// A strip of a given width along a polyline: what a stroke becomes as a road (say, along a
// sculpted ridge), in any plane frame.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace ps::tin {

struct Strip {
  std::vector<Eigen::Vector2d> xy;  // two per centre point: left then right of the direction
  std::vector<std::array<std::uint32_t, 3>> triangles;  // two per segment, counter-clockwise
};

// The polyline is first simplified (Douglas-Peucker) to within the width: a tracked stroke's
// jitter would fold the strip over itself; points where the path turns back (by more than 100
// degrees) are dropped, as no strip follows them. Each kept point's two vertices are offset by half
// the width along the bisector of its segments (a mitre, limited to twice the half width at sharp
// turns). Throws core::InputError for a width that is not positive or a polyline of fewer than
// two distinct points.
Strip stripAlong(const std::vector<Eigen::Vector2d>& centre, double width);

}  // namespace ps::tin
