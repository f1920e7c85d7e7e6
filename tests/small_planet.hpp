#pragma once
// A 20 km lat-long planet with 100 m bumps and an edit pipeline on it: small enough that one
// stroke of the TIN sand tool (1,200 m stamps) covers a fair part of it. The TIN sand and
// haptics tests share it.
#include <Eigen/Core>
#include <memory>

#include "core/latlong_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

namespace ps::testkit {

inline constexpr double kSmallPlanetRadius = 20e3;  // m

struct SmallPlanet {
  explicit SmallPlanet(int level = 8) : chart(sandtest::sphereChart(level, kSmallPlanetRadius)) {}
  std::shared_ptr<const core::LatLongChart> chart;  // level 8: 257^2, 490 m cells
  terrain::Terrain t{chart, bumpyHeights(*chart, 3, 100.0)};
  edit::EditPipeline pipe{t};
};

// The point h metres above the small planet's sphere at (latDeg, lonDeg).
inline Eigen::Vector3d aboveSmallPlanet(double latDeg, double lonDeg, double h) {
  return edittest::latLon(latDeg, lonDeg, kSmallPlanetRadius + h, 1.0);
}

}  // namespace ps::testkit
