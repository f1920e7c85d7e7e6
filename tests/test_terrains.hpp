#pragma once
// Terrains for tests: rough, deterministic relief computed from each vertex's 3D direction (so
// seam twins and pole rows are consistent), independent of the production relief generator.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "terrain/relief.hpp"
#include "terrain/terrain.hpp"

namespace ps::testkit {

inline constexpr double kEarthRadius = 6372790.0;

inline std::vector<float> bumpyHeights(const core::Chart& chart, std::uint32_t seed,
                                       double amplitude, int bumps = 40) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  struct Bump {
    Eigen::Vector3d c;
    double width, height;
  };
  std::vector<Bump> list;
  for (int i = 0; i < bumps; ++i) {
    Eigen::Vector3d c(uni(rng), uni(rng), uni(rng));
    if (i == 0) c = Eigen::Vector3d(0, 0, 1);   // a bump on the north pole
    if (i == 1) c = Eigen::Vector3d(-1, 0, 0);  // and one on the seam
    list.push_back({c.normalized(), 0.02 + 0.3 * std::abs(uni(rng)), amplitude * uni(rng)});
  }
  const core::GridSize g = chart.grid();
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const Eigen::Vector3d d = chart.up(u, v);
      double x = 0.15 * amplitude * std::sin(23 * d.x() + 7) * std::cos(19 * d.y() - 3) *
                 std::sin(29 * d.z());
      for (const Bump& b : list)
        x += b.height * std::exp(-(d - b.c).squaredNorm() / (b.width * b.width));
      h[g.index(u, v)] = float(x);
    }
  }
  return h;
}

inline std::shared_ptr<const core::LatLongChart> earthChart(int n) {
  return std::make_shared<core::LatLongChart>(core::GridSize(n), kEarthRadius);
}

// An Earth-sized lat-long planet with every height h: a sphere, whose silhouette, shadow and
// surface are known exactly.
inline terrain::Terrain levelTerrain(int n, float h = 0.0f) {
  auto chart = earthChart(n);
  return terrain::Terrain(chart, std::vector<float>(chart->grid().count(), h));
}

inline terrain::Terrain bumpyTerrain(int n, std::uint32_t seed = 1, double amplitude = 8000.0,
                                     terrain::ErrorRule rule = terrain::ErrorRule::kHybridExact) {
  auto chart = earthChart(n);
  return terrain::Terrain(chart, bumpyHeights(*chart, seed, amplitude), rule);
}

// The production relief (terrain/relief.hpp) on an Earth-sized lat-long planet.
inline terrain::Terrain reliefTerrain(int n, std::uint64_t seed) {
  auto chart = earthChart(n);
  terrain::ReliefParams p;
  p.seed = seed;
  return terrain::Terrain(chart, terrain::generateRelief(*chart, p));
}

// Both of the octahedral chart's mappings, for tests that run on each.
inline constexpr std::array<core::OctahedralChart::Mapping, 2> kOctahedralMappings{
    core::OctahedralChart::Mapping::kEqualArea, core::OctahedralChart::Mapping::kCentral};

inline std::shared_ptr<const core::OctahedralChart> octahedralChart(
    int n, core::OctahedralChart::Mapping mapping = core::OctahedralChart::Mapping::kEqualArea) {
  return std::make_shared<core::OctahedralChart>(core::GridSize(n), kEarthRadius, mapping);
}

inline terrain::Terrain bumpyOctahedralTerrain(
    int n, std::uint32_t seed = 1, double amplitude = 8000.0,
    core::OctahedralChart::Mapping mapping = core::OctahedralChart::Mapping::kEqualArea) {
  auto chart = octahedralChart(n, mapping);
  return terrain::Terrain(chart, bumpyHeights(*chart, seed, amplitude));
}

}  // namespace ps::testkit
