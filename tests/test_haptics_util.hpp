#pragma once
// Helpers shared by the haptics tests (tests/test_haptics_*.cpp, tests/test_stress_haptics.cpp):
// analytic flat sand for ForceModel, sphere planets (flat or with relief) for HapticCore and the
// session, and directions by latitude and longitude.
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "haptics/force_model.hpp"
#include "haptics/settings.hpp"
#include "terrain/terrain.hpp"
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

}  // namespace ps::haptictest
