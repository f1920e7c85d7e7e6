#pragma once
// How high a point (the tool tip) is above a planet's surface, on any chart with a centre: what
// the AR scene asks each frame to decide whether the tool touches (tracking::SceneTracker).
#include <Eigen/Core>
#include <optional>

#include "core/grid.hpp"
#include "terrain/terrain.hpp"

namespace ps::edit {

// The point's control vertex (edit::nearestVertex: the grid vertex nearest on the surface at
// height 0) and its height above the sculpted surface there, in planet metres: the distance
// from the surface at height 0 along its normal (negative below it) less the control vertex's
// height. On a sphere |p| - R - h, as the scene measured it before other charts; on a torus the
// distance from the tube's centre circle less the minor radius; on a cylinder the distance from
// the axis less its radius, and beyond an open end (|z| > length / 2) the distance to the rim
// circle at the control vertex's height (positive: the ends are no surface, only their rims
// are). nullopt where p has no nearest vertex (the sphere's centre, the torus's axis and centre
// circle, the cylinder's axis, a point not finite) and on the flat chart.
struct SurfaceContact {
  core::GridPoint control;
  double height = 0;
};
std::optional<SurfaceContact> surfaceContact(const terrain::Terrain& planet,
                                             const Eigen::Vector3d& p);

}  // namespace ps::edit
