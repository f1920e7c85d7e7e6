// Roads stitched into a planet's welded TIN in their own planes (tin/plane_stitch): the surface
// unchanged (its area and the volume it encloses, to rounding), closed, each road vertex on its
// ray from the centre, and the road's footprint exactly the road group's; refusals by name.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "core/input_error.hpp"
#include "io/road_placement.hpp"
#include "io/tin_export.hpp"
#include "stress_util.hpp"
#include "test_terrains.hpp"
#include "tin/plane_stitch.hpp"
#include "tin/strip.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::tin {
namespace {

struct Planet {
  terrain::Terrain terrain;
  SurfaceMesh surface;
};

Planet weldedPlanet(terrain::Terrain t) {
  Planet p{std::move(t), {}};
  SampleField field = io::terrainSampleField(p.terrain);
  field.uniformTolerance = 2000.0;
  const Tin tin = buildTin(field, {});
  const WeldedMesh welded = weldTin(field, tin);
  p.surface.positions.assign(welded.vertices, Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < tin.xy.size(); ++v)
    p.surface.positions[welded.vertexOf[v]] =
        field.positionAt(tin.xy[v].x(), tin.xy[v].y(), tin.h[v]);
  p.surface.triangles = welded.triangles;
  return p;
}

double surfaceArea(const SurfaceMesh& m) {
  double a = 0;
  for (const auto& t : m.triangles)
    a +=
        0.5 *
        (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).norm();
  return a;
}

double enclosedVolume(const SurfaceMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles)
    v += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) / 6.0;
  return v;
}

RoadPlane planeAt(const core::Chart& chart, const std::array<double, 3>& at) {
  const io::RoadFrame f = io::roadFrame(chart, at, "test");
  return {Eigen::Vector3d::Zero(), f.origin, f.up, f.x, f.y};
}

// A point of the plane as seen from the centre (the inverse of the stitch's lift's ray).
Eigen::Vector2d seenInPlane(const RoadPlane& plane, const Eigen::Vector3d& p) {
  const double reach = (plane.origin - plane.centre).dot(plane.up);
  const Eigen::Vector3d s = (p - plane.centre) * (reach / (p - plane.centre).dot(plane.up)) -
                            (plane.origin - plane.centre);
  return {s.dot(plane.x), s.dot(plane.y)};
}

double area2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// A random road: a strip 10-40 km wide along a gently turning path of 2-6 legs of 50-200 km.
Strip randomRoad(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int legs = 2 + int(5 * unit(rng));
  double heading = 2 * std::numbers::pi * unit(rng);
  std::vector<Eigen::Vector2d> path{{-60000 * unit(rng), -60000 * unit(rng)}};
  for (int k = 0; k < legs; ++k) {
    heading += 0.7 * (unit(rng) - 0.5);
    const double length = 50000 + 150000 * unit(rng);
    path.push_back(path.back() + length * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
  }
  return stripAlong(path, 10000 + 30000 * unit(rng));
}

TEST(PlaneStitch, RandomRoadsLeaveThePlanetsSurfaceClosedAndUnchanged) {
  std::vector<Planet> planets;
  planets.push_back(weldedPlanet(testkit::bumpyTerrain(6, 2, 20000.0)));
  planets.push_back(weldedPlanet(testkit::bumpyOctahedralTerrain(6, 2, 20000.0)));
  planets.push_back(weldedPlanet(testkit::levelTerrain(7)));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int trials = testkit::underAsan() ? 6 : 24;
  for (const Planet& planet : planets) {
    const double area = surfaceArea(planet.surface), volume = enclosedVolume(planet.surface);
    const std::size_t n = planet.surface.positions.size();
    int crossed = 0;  // roads that cross a terrain edge (the rest lie inside one triangle)
    for (int trial = 0; trial < trials; ++trial) {
      // A third within a degree of a pole (lat-long's, which the grid's stitch cannot take).
      const double lat = trial % 3 == 0 ? (trial % 2 ? 1 : -1) * (90 - unit(rng))
                                        : std::asin(2 * unit(rng) - 1) * 180 / std::numbers::pi;
      const std::array<double, 3> at{lat, 360 * unit(rng) - 180, 360 * unit(rng)};
      SCOPED_TRACE(planet.terrain.chart().name() + " at " + std::to_string(at[0]) + ", " +
                   std::to_string(at[1]) + " heading " + std::to_string(at[2]));
      const Strip road = randomRoad(rng);
      const RoadPlane plane = planeAt(planet.terrain.chart(), at);
      const PlaneStitch s = stitchInPlane(planet.surface, plane, road.xy, road.triangles);
      const MeshTopology top = meshTopology(s.mesh.positions.size(), s.mesh.triangles);
      EXPECT_EQ(top.euler(), 2);
      EXPECT_EQ(top.borderEdges, 0u);
      EXPECT_EQ(top.nonManifoldEdges, 0u);
      EXPECT_EQ(top.degenerate, 0u);
      // The surface is the terrain's: an added vertex off it, a face left out or laid twice, or
      // one turned over would change its area or the volume it holds.
      EXPECT_NEAR(surfaceArea(s.mesh), area, 1e-10 * area);
      EXPECT_NEAR(enclosedVolume(s.mesh), volume, 1e-10 * volume);
      EXPECT_LT(s.addedVertexErrorM, 1e-6);
      crossed += s.crossingVertices > 0;
      // The road group is the road's footprint, seen in its plane.
      double roadArea = 0, grouped = 0;
      for (const auto& t : road.triangles)
        roadArea += std::abs(area2(road.xy[t[0]], road.xy[t[1]], road.xy[t[2]]));
      for (std::size_t k = 0; k < s.mesh.triangles.size(); ++k) {
        if (!s.onRoad[k]) continue;
        const auto& t = s.mesh.triangles[k];
        grouped += area2(seenInPlane(plane, s.mesh.positions[t[0]]),
                         seenInPlane(plane, s.mesh.positions[t[1]]),
                         seenInPlane(plane, s.mesh.positions[t[2]]));
      }
      EXPECT_NEAR(grouped, roadArea, 1e-8 * roadArea);
      // Each road vertex is a vertex of the mesh, on its own ray from the centre.
      for (const Eigen::Vector2d& p : road.xy) {
        double nearest = INFINITY;
        for (std::size_t v = 0; v < s.mesh.positions.size(); ++v)
          nearest = std::min(nearest, (seenInPlane(plane, s.mesh.positions[v]) - p).norm());
        EXPECT_LT(nearest, 1e-6) << p.transpose();
      }
      // Outside the re-meshed region nothing moved.
      for (std::size_t v = 0; v < n; ++v)
        ASSERT_EQ(s.mesh.positions[v], planet.surface.positions[v]);
    }
    EXPECT_GE(crossed, trials / 2);
  }
}

TEST(PlaneStitch, RoadsThatAreNotProperMeshesOrTooLargeAreRefusedByName) {
  const Planet planet = weldedPlanet(testkit::bumpyTerrain(5, 3, 20000.0));
  const RoadPlane plane = planeAt(planet.terrain.chart(), {90.0, 0.0, 0.0});
  auto refused = [&](const std::vector<Eigen::Vector2d>& xy,
                     const std::vector<std::array<std::uint32_t, 3>>& tris,
                     const std::string& why) {
    try {
      stitchInPlane(planet.surface, plane, xy, tris);
      ADD_FAILURE() << "accepted a road refused for " << why;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  const double k = 100000;
  const std::vector<Eigen::Vector2d> square{{-k, -k}, {k, -k}, {k, k}, {-k, k}};
  refused(square, {{0, 1, 2}, {0, 2, 1}}, "overlaps itself");
  refused(square, {{0, 1, 2}, {0, 0, 3}}, "degenerate");
  refused(square, {{0, 1, 2}, {1, 3, 0}}, "crosses itself");
  const double huge = 1.2 * planet.terrain.chart().sphereRadius();
  refused({{-huge, -huge}, {huge, -huge}, {huge, huge}}, {{0, 1, 2}}, "45 degrees");
  EXPECT_NO_THROW(stitchInPlane(planet.surface, plane, square, {{0, 1, 2}, {0, 2, 3}}));
}

}  // namespace
}  // namespace ps::tin
