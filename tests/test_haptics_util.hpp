#pragma once
// Helpers shared by the haptics tests (tests/test_haptics_*.cpp, tests/test_stress_haptics.cpp):
// analytic flat sand for ForceModel, sphere planets (flat or with relief) for HapticCore and the
// session, and directions by latitude and longitude.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "edit/edit_pipeline.hpp"
#include "haptics/force_log.hpp"
#include "haptics/force_model.hpp"
#include "haptics/force_path.hpp"
#include "haptics/settings.hpp"
#include "sand/sand_grid.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"

namespace ps::haptictest {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kR = 6372790.0;  // m: the planet
inline constexpr double kGlobe = 0.06;   // m: the displayed planet (tracking's default)

// A flat sand surface z = 0 (device space), normal +z: depth = -z.
inline haptics::TickInput flatInput(double t, const Eigen::Vector3d& p) {
  haptics::TickInput in;
  in.time = t;
  in.position = p;
  in.contact.valid = true;
  in.contact.depth = -p.z();
  in.contact.normal = Eigen::Vector3d::UnitZ();
  return in;
}

// Settings whose exponential law is felt: slope k_s k_c = 200 N/m at the surface, reaching the
// 2000 N/m stiffness limit at d* = ln(10) / 100 = 23 mm.
inline haptics::HapticSettings softSand() {
  haptics::HapticSettings s;
  s.constants = {2.0, 100.0, 1.0};
  return s;
}

// Point at latitude/longitude (degrees) and distance r from the centre.
inline Eigen::Vector3d latLon(double latDeg, double lonDeg, double r = 1.0) {
  const double la = latDeg * std::numbers::pi / 180, lo = lonDeg * std::numbers::pi / 180;
  return r *
         Eigen::Vector3d(std::cos(lo) * std::cos(la), std::sin(lo) * std::cos(la), std::sin(la));
}

// A lat-long planet of radius kR with every height h.
inline terrain::Terrain flatPlanet(int n, float h = 2000.0f) {
  auto chart = sandtest::sphereChart(n, kR);
  return terrain::Terrain(chart, std::vector<float>(chart->grid().count(), h));
}

// A lat-long planet with smooth relief (a few km), seam and poles consistent.
inline terrain::Terrain reliefPlanet(int n) {
  auto chart = sandtest::sphereChart(n, kR);
  const double m = chart->grid().m();
  auto h = sandtest::heightsFrom(*chart, [&](int u, int v) {
    const double lon = 2 * std::numbers::pi * u / m, lat = std::numbers::pi * v / m;
    return 3000.0 * std::sin(3 * lon) * std::sin(lat) * std::sin(lat) + 500.0 * std::cos(2 * lat);
  });
  return terrain::Terrain(chart, std::move(h));
}

// The force log and the heights after a stroke, and what the log and the heights show.
struct StrokeOutcome {
  std::string log;
  std::vector<float> heights;
  int touching = 0;        // ticks touching the sand
  int faults = 0;          // ticks with a fault (after the first, which has no sample yet)
  double maxForce = 0.0;   // N
  double volumeDrift = 0;  // |volume change| / the layer's sum of A |h|
};

// A stroke over 3 s at 30 frames a second through ForcePath on a planet of one height `layer`
// (m), `scale` planet metres to the device metre: pressed in from 3 mm (device) above the
// surface to 1.5 mm below it in the first second, dragged along x from -1 to 1 in the second,
// lifted in the third; `tip(altitude, x)` places the tip (planet frame). It stamps more than
// 3 times, and the heights stay consistent, their bounds those of a full rebuild.
inline StrokeOutcome pressDragLift(const std::shared_ptr<const core::Chart>& chart, float layer,
                                   double scale,
                                   const std::function<Eigen::Vector3d(double, double)>& tip) {
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), layer));
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  haptics::ForcePathConfig cfg;
  cfg.map.scale = scale;
  haptics::ForcePath s(t, &pipe, cfg);
  std::ostringstream log;
  s.setLog(&log);
  const double above = 0.003 * scale, below = -0.0015 * scale;
  for (int f = 0; f <= 90; ++f) {
    const double time = f / 30.0;
    double alt, x = -1.0;
    if (time < 1) {
      alt = above + (below - above) * time;
    } else if (time < 2) {
      alt = below, x = -1.0 + 2.0 * (time - 1);
    } else {
      alt = below + (above - below) * std::min(1.0, time - 2), x = 1.0;
    }
    s.onFrame(tip(alt, x), time);
  }
  EXPECT_GT(s.totalStamps(), 3u);
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  StrokeOutcome out{log.str(), std::vector<float>(t.heights().begin(), t.heights().end())};
  std::istringstream in(out.log);
  for (const haptics::ForceRecord& r : haptics::readForceLog(in)) {
    out.touching += r.touching;
    out.faults += r.time > 0 && r.fault != haptics::Fault::kNone;
    out.maxForce = std::max(out.maxForce, r.force.norm());
  }
  const sand::SandGrid grid(chart);
  const std::vector<float> before(chart->grid().count(), layer);
  out.volumeDrift =
      std::abs(grid.volume(out.heights) - grid.volume(before)) / grid.absVolume(before);
  return out;
}

}  // namespace ps::haptictest
