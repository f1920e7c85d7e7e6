// A road laid on a planet (io/road_placement.hpp): every point of every laid edge, taken back from
// the surface into the road's plane, lies within the tolerance of the road's footprint, on the
// sphere charts at random places (the poles, the folds, their ends and the seam included) and on
// the torus and the cylinder; a road too large for its place on a tube is refused by name. Stitched
// into a terrain's TIN, the road is draped over the mesh onto that footprint.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <random>

#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "io/road_placement.hpp"
#include "io/road_unfolding.hpp"
#include "io/tin_export.hpp"
#include "stress_util.hpp"
#include "terrain/terrain.hpp"
#include "test_terrains.hpp"
#include "tin/overlay.hpp"

using namespace ps;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kHalfWidth = 5000, kHalfLength = 100000;

// 200 x 10 km along +y, 16 triangles of 25 km edges (the CLI test's strip).
io::ObjTriangles strip() {
  io::ObjTriangles s;
  for (int i = 0; i <= 8; ++i)
    s.vertices.emplace_back(-kHalfWidth, -kHalfLength + 25000 * i, 0),
        s.vertices.emplace_back(kHalfWidth, -kHalfLength + 25000 * i, 0);
  for (std::uint32_t i = 0; i < 8; ++i)
    s.triangles.push_back({2 * i, 2 * i + 1, 2 * i + 3}),
        s.triangles.push_back({2 * i, 2 * i + 3, 2 * i + 2});
  return s;
}

// The place and the surface's outward normal anywhere, written from each surface's formula (not
// from the code under test).
struct Place {
  Eigen::Vector3d origin, up, x, y;
};

Place placeOn(const core::Chart& chart, double a, double b, double heading) {
  Place p;
  double azimuth = a * kDeg;
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart)) {
    const Eigen::Vector3d out(std::cos(azimuth), std::sin(azimuth), 0);
    p.up = std::cos(b * kDeg) * out + Eigen::Vector3d(0, 0, std::sin(b * kDeg));
    p.origin = torus->majorRadius() * out + torus->minorRadius() * p.up;
  } else if (const auto* tube = dynamic_cast<const core::CylinderChart*>(&chart)) {
    p.up = {std::cos(azimuth), std::sin(azimuth), 0};
    p.origin = tube->tubeRadius() * p.up + Eigen::Vector3d(0, 0, b);
  } else {
    azimuth = b * kDeg;
    p.up = {std::cos(a * kDeg) * std::cos(azimuth), std::cos(a * kDeg) * std::sin(azimuth),
            std::sin(a * kDeg)};
    p.origin = chart.sphereRadius() * p.up;
  }
  const Eigen::Vector3d east(-std::sin(azimuth), std::cos(azimuth), 0);
  const Eigen::Vector3d north = p.up.cross(east);
  p.x = east * std::cos(heading * kDeg) - north * std::sin(heading * kDeg);
  p.y = north * std::cos(heading * kDeg) + east * std::sin(heading * kDeg);
  return p;
}

Eigen::Vector3d normalAt(const core::Chart& chart, const Eigen::Vector3d& s) {
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart)) {
    const Eigen::Vector3d centre =
        torus->majorRadius() * Eigen::Vector3d(s.x(), s.y(), 0).normalized();
    return (s - centre).normalized();
  }
  if (dynamic_cast<const core::CylinderChart*>(&chart))
    return Eigen::Vector3d(s.x(), s.y(), 0).normalized();
  return s.normalized();
}

// The largest distance outside the strip's footprint of points along every laid edge: each point
// put on the surface from the grid, then along the surface's normal into the road's plane.
double offFootprint(const core::Chart& chart, double m, const Place& place, const tin::Road& road) {
  double worst = 0;
  for (const auto& t : road.triangles)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d a = road.xy[t[std::size_t(k)]],
                            b = road.xy[t[std::size_t((k + 1) % 3)]];
      for (int i = 0; i <= 8; ++i) {
        const Eigen::Vector2d g = io::intoGrid(chart, m, a + (b - a) * (i / 8.0));
        const Eigen::Vector3d s = chart.positionAt(g.x(), g.y(), 0.0);
        const Eigen::Vector3d n = normalAt(chart, s);
        const Eigen::Vector3d q = s + n * ((place.origin - s).dot(place.up) / n.dot(place.up));
        const double x = (q - place.origin).dot(place.x), y = (q - place.origin).dot(place.y);
        worst = std::max({worst, std::abs(x) - kHalfWidth, std::abs(y) - kHalfLength});
      }
    }
  return worst;
}

}  // namespace

TEST(RoadPlacement, LaidEdgesFollowTheSphereWithinTheTolerance) {
  const double r = 1737400, tolerance = 50;
  const core::OctahedralChart octa(core::GridSize(8), r);
  const core::LatLongChart latlong(core::GridSize(8), r);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int laid = 0, cut = 0, wouldStray = 0;
  for (const core::Chart* chart :
       {static_cast<const core::Chart*>(&octa), static_cast<const core::Chart*>(&latlong)}) {
    const double m = chart->grid().m();
    const double polar = 90.0;  // lat-long's pole rows too (refused until 2026-12-07)
    for (int trial = 0; trial < 40; ++trial) {
      // Half of them near a pole, where the chart bends straight grid lines most.
      const double lat =
          trial % 2 ? (2 * unit(rng) - 1) * polar : (trial % 4 ? 1 : -1) * (polar - 6 * unit(rng));
      const double lon = 360 * unit(rng) - 180, heading = 360 * unit(rng);
      const io::LaidRoad road =
          io::layRoadOnPlanet(strip(), *chart, m, {lat, lon, heading}, tolerance, "road");
      ++laid;
      cut += road.halvedEdges > 0;
      EXPECT_LE(road.strayM, tolerance)
          << chart->name() << " at " << lat << ", " << lon << " heading " << heading << ", halved "
          << road.halvedEdges;
      const double off = offFootprint(*chart, m, placeOn(*chart, lat, lon, heading), road.road);
      EXPECT_LT(off, 1.25 * tolerance)
          << chart->name() << " at " << lat << ", " << lon << " heading " << heading << ": "
          << road.road.triangles.size() << " triangles, " << road.halvedEdges << " halved";
      // Without halving the same road strays beyond the tolerance (so the check can fail).
      if (road.halvedEdges > 0) {
        const io::LaidRoad coarse =
            io::layRoadOnPlanet(strip(), *chart, m, {lat, lon, heading}, 1e9, "road");
        wouldStray += offFootprint(*chart, m, placeOn(*chart, lat, lon, heading), coarse.road) >
                      1.25 * tolerance;
      }
    }
  }
  EXPECT_EQ(laid, 80);
  EXPECT_GT(cut, 10);
  EXPECT_GT(wouldStray, 5);
}

TEST(RoadPlacement, RoadsAroundTheEndsOfTheOctahedralFoldsAreLaidInTwoHalves) {
  // The ends of the folds are the equator at longitudes 0, 90, 180 and -90, where the grid turns
  // half round while the sphere turns whole (refused until 2026-12-07).
  const double r = 1737400, tolerance = 50;
  const core::OctahedralChart octa(core::GridSize(8), r);
  const double m = octa.grid().m();
  for (const auto& at : {std::array<double, 3>{0, -90, 0}, std::array<double, 3>{0, 0, 45},
                         std::array<double, 3>{0.1, 90, 90}, std::array<double, 3>{-1, 180, 30},
                         std::array<double, 3>{0, 0.1, 0}}) {
    const io::LaidRoad road = io::layRoadOnPlanet(strip(), octa, m, at, tolerance, "road");
    EXPECT_GE(road.pieces, 2) << at[0] << ", " << at[1];
    EXPECT_LE(road.strayM, tolerance);
    EXPECT_LT(offFootprint(octa, m, placeOn(octa, at[0], at[1], at[2]), road.road),
              1.25 * tolerance)
        << at[0] << ", " << at[1];
  }
  // A square whose first vertex lies on the end itself (the unfolding may not start there: from
  // the end both sides of the fold continue an edge alike).
  io::ObjTriangles fan;
  fan.vertices = {
      {0, 0, 0}, {kHalfWidth, 0, 0}, {0, kHalfWidth, 0}, {-kHalfWidth, 0, 0}, {0, -kHalfWidth, 0}};
  fan.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}};
  const io::LaidRoad road = io::layRoadOnPlanet(fan, octa, m, {0, 180, 10}, tolerance, "fan");
  EXPECT_EQ(road.pieces, 2);
  EXPECT_LE(road.strayM, tolerance);
}

// Over one of lat-long's poles, where a whole grid row is one point (refused until 2026-12-07):
// the road gets a vertex at the pole, spread along the pole's row under each of its neighbours,
// so that its triangles cover the whole row (the pole's every direction) once, and its edges
// follow the sphere as anywhere else.
TEST(RoadPlacement, RoadsOverLatLongsPolesCoverThePolesRow) {
  const double r = 1737400, tolerance = 50;
  const core::LatLongChart latlong(core::GridSize(8), r);
  const double m = latlong.grid().m();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 24; ++trial) {
    // Within 0.12 degrees (3.6 km) of a pole: inside the 10 km wide strip at every heading.
    const double side = trial % 2 ? 1 : -1;
    const double lat = side * (90 - 0.12 * unit(rng)),
                 lon = trial == 0 ? 180 : 360 * unit(rng) - 180;
    const double heading = 360 * unit(rng);
    SCOPED_TRACE(std::to_string(lat) + ", " + std::to_string(lon) + " heading " +
                 std::to_string(heading));
    const io::LaidRoad road =
        io::layRoadOnPlanet(strip(), latlong, m, {lat, lon, heading}, tolerance, "road");
    EXPECT_LE(road.strayM, tolerance);
    EXPECT_LT(offFootprint(latlong, m, placeOn(latlong, lat, lon, heading), road.road),
              1.25 * tolerance);
    // The pole's row, as the triangles' edges along it cover it (each edge moved into the grid).
    const double row = side > 0 ? m : 0;
    std::vector<std::pair<double, double>> along;
    double turn = 0;  // the grid triangles' summed signed area: all one way
    double turnAbs = 0;
    for (const auto& t : road.road.triangles) {
      const Eigen::Vector2d a = road.road.xy[t[0]], b = road.road.xy[t[1]], c = road.road.xy[t[2]];
      const double area = 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
      turn += area, turnAbs += std::abs(area);
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d p = road.road.xy[t[std::size_t(k)]],
                              q = road.road.xy[t[std::size_t((k + 1) % 3)]];
        if (p.y() == row && q.y() == row) {
          const double lo = std::clamp(std::min(p.x(), q.x()), 0.0, m),
                       hi = std::clamp(std::max(p.x(), q.x()), 0.0, m);
          if (hi > lo) along.emplace_back(lo, hi);
        }
      }
    }
    EXPECT_NEAR(std::abs(turn), turnAbs, 1e-9 * turnAbs) << "a grid triangle is turned over";
    std::sort(along.begin(), along.end());
    double reached = 0;
    for (const auto& [lo, hi] : along)
      if (lo <= reached + 1e-9 * m) reached = std::max(reached, hi);
    EXPECT_GE(reached, m * (1 - 1e-12)) << along.size() << " edges along the pole's row";
  }
}

// A road whose pole lies among its inner vertices only (no edge from it reaches the border, so
// it cannot be parted there) is refused by name, naming the road.
TEST(RoadPlacement, APoleAmongInnerVerticesOnlyIsRefusedByName) {
  const core::LatLongChart latlong(core::GridSize(8), 1737400);
  io::ObjTriangles grid;  // 4 x 4 vertices 10 km apart, centred on the place
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)
      grid.vertices.emplace_back(10000.0 * i - 15000, 10000.0 * j - 15000, 0);
  for (std::uint32_t j = 0; j < 3; ++j)
    for (std::uint32_t i = 0; i < 3; ++i) {
      const std::uint32_t a = 4 * j + i;
      grid.triangles.push_back({a, a + 1, a + 5}), grid.triangles.push_back({a, a + 5, a + 4});
    }
  try {
    io::layRoadOnPlanet(grid, latlong, latlong.grid().m(), {90, 0, 0}, 50, "square.obj");
    ADD_FAILURE() << "a pole among inner vertices was laid";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("square.obj: ", 0), 0u) << what;
    EXPECT_NE(what.find("no edge from it reaches the road's border"), std::string::npos) << what;
  }
  // The same square placed so that the pole lies about 12 km north of its middle, in its top row
  // of triangles, which have corners on the border: laid over the pole.
  const io::LaidRoad top =
      io::layRoadOnPlanet(grid, latlong, latlong.grid().m(), {89.6, 0, 0}, 50, "square.obj");
  EXPECT_TRUE(top.holdsPole);
  EXPECT_LE(top.strayM, 50);
}

TEST(RoadPlacement, RoadsLieOnTheTorusAndTheCylinderAcrossTheirSeams) {
  const double tolerance = 50;
  const core::TorusChart torus(core::GridSize(8), 4.5e6, 1.8e6);
  const core::CylinderChart tube(core::GridSize(8), 6e5, 4e6);
  struct Case {
    const core::Chart* chart;
    double a, b, heading;
    int pieces;
  };
  for (const Case& c :
       {Case{&torus, 30, 45, 20, 1}, Case{&torus, 0, 90, 0, 2}, Case{&torus, 90, 0, 70, 2},
        Case{&torus, 0.01, 0.01, 45, 4}, Case{&torus, 10, 180, 90, 1}, Case{&tube, 45, 1e6, 30, 1},
        Case{&tube, 0, -5e5, 90, 2}}) {
    const double m = c.chart->grid().m();
    const io::LaidRoad road =
        io::layRoadOnPlanet(strip(), *c.chart, m, {c.a, c.b, c.heading}, tolerance, "road");
    EXPECT_EQ(road.pieces, c.pieces) << c.chart->name() << " at " << c.a << ", " << c.b;
    EXPECT_LE(road.strayM, tolerance);
    EXPECT_LT(offFootprint(*c.chart, m, placeOn(*c.chart, c.a, c.b, c.heading), road.road),
              1.25 * tolerance)
        << c.chart->name() << " at " << c.a << ", " << c.b;
  }
  // A road longer than the torus's hole is wide, laid along the inner equator, would reach round
  // to the outside: refused by name.
  io::ObjTriangles long_ = strip();
  for (Eigen::Vector3d& p : long_.vertices) p.y() *= 50;  // 10,000 km
  try {
    io::layRoadOnPlanet(long_, torus, torus.grid().m(), {0, 180, 90}, tolerance, "long.obj");
    ADD_FAILURE() << "a road round the torus's hole was laid";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("long.obj: ", 0), 0u) << what;
    EXPECT_TRUE(what.find("folds over") != std::string::npos ||
                what.find("too far round the torus") != std::string::npos ||
                what.find("has no place") != std::string::npos)
        << what;
  }
  // A place off the cylinder's length.
  EXPECT_THROW(io::layRoadOnPlanet(strip(), tube, tube.grid().m(), {0, 3e6, 0}, tolerance, "r"),
               core::InputError);
}

TEST(RoadPlacement, APlaceOnTheSurfaceIsWhereItsFrameStands) {
  // `road` names a stroke's start by placeOf, and overlay lays the road's plane there by
  // roadFrame: on every chart with places the two are inverse, and the frame's up is the
  // surface's normal.
  const core::OctahedralChart octa(core::GridSize(6), 1737400);
  const core::LatLongChart latlong(core::GridSize(6), 1737400);
  const core::TorusChart torus(core::GridSize(6), 4.5e6, 1.8e6);
  const core::CylinderChart tube(core::GridSize(6), 6e5, 4e6);
  std::mt19937 rng(3);
  for (const core::Chart* chart :
       std::initializer_list<const core::Chart*>{&octa, &latlong, &torus, &tube}) {
    const double m = chart->grid().m();
    std::uniform_real_distribution<double> in(0.5, m - 0.5);
    for (int k = 0; k < 100; ++k) {
      const Eigen::Vector3d p = chart->positionAt(in(rng), in(rng), 0.0);
      const std::array<double, 2> place = io::placeOf(*chart, p);
      const io::RoadFrame f = io::roadFrame(*chart, {place[0], place[1], 0}, "r");
      EXPECT_LT((f.origin - p).norm(), 1e-6) << chart->name() << " " << p.transpose();
      EXPECT_LT((f.up - io::surfaceNormal(*chart, p)).norm(), 1e-8) << chart->name();
      EXPECT_NEAR(f.x.dot(f.up), 0.0, 1e-12);
      EXPECT_NEAR(f.y.dot(f.up), 0.0, 1e-12);
      EXPECT_NEAR(f.x.cross(f.y).dot(f.up), 1.0, 1e-12) << "x, y and up turn as east, north, up";
    }
  }
  const core::FlatChart flat(core::GridSize(6), 1000.0, 1000.0);
  EXPECT_THROW(io::placeOf(flat, Eigen::Vector3d(1, 2, 0)), core::InputError);
}

namespace {

// Where a point of the stitched mesh lies in the road's plane, taken there along the surface's
// normal through it (the line the road's own point was put on the surface by).
Eigen::Vector2d inRoadPlane(const core::Chart& chart, const Place& place,
                            const Eigen::Vector3d& p) {
  const Eigen::Vector3d n = normalAt(chart, p);
  const Eigen::Vector3d q = p + n * ((place.origin - p).dot(place.up) / n.dot(place.up));
  return {(q - place.origin).dot(place.x), (q - place.origin).dot(place.y)};
}

}  // namespace

TEST(RoadPlacement, AStitchedRoadIsDrapedOverTheTerrainMeshOntoItsFootprint) {
  // A smooth Earth-sized planet's TIN at a 200 m error: flat triangles across many grid cells,
  // whose blend of their corners puts a grid point up to kilometres along the surface from its
  // chart point near the poles (before 2026-12-07 a road's vertices and crossings were put there).
  const double tolerance = 200;
  struct Case {
    std::shared_ptr<const core::Chart> chart;
    double a, b, heading;
  };
  std::vector<Case> cases;
  const auto octa =
      std::make_shared<core::OctahedralChart>(core::GridSize(7), testkit::kEarthRadius);
  const auto latlong =
      std::make_shared<core::LatLongChart>(core::GridSize(7), testkit::kEarthRadius);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int placements = testkit::underAsan() ? 8 : 16;  // an overlay of the whole TIN each
  for (int k = 0; k < placements; ++k) {
    const bool isOcta = k % 2 == 0;
    const double polar = isOcta ? 90.0 : 84.0;  // lat-long's pole rows are refused
    const double lat =
        k % 4 < 2 ? (2 * unit(rng) - 1) * polar : (k % 8 < 4 ? 1 : -1) * (polar - 8 * unit(rng));
    cases.push_back({isOcta ? std::shared_ptr<const core::Chart>(octa)
                            : std::shared_ptr<const core::Chart>(latlong),
                     lat, 360 * unit(rng) - 180, 360 * unit(rng)});
  }
  cases.push_back(
      {std::make_shared<core::TorusChart>(core::GridSize(7), 4.5e6, 1.8e6), 30, 45, 20});
  cases.push_back(
      {std::make_shared<core::CylinderChart>(core::GridSize(7), 6e5, 4e6), 45, 1e6, 30});
  struct Ground {
    terrain::Terrain terrain;
    tin::SampleField field;
    tin::Tin tin;
  };
  std::map<const core::Chart*, std::unique_ptr<Ground>> grounds;
  int whole = 0;
  double farthestMove = 0;
  for (const Case& c : cases) {
    std::unique_ptr<Ground>& g = grounds[c.chart.get()];
    if (!g) {
      g.reset(new Ground{{c.chart, testkit::bumpyHeights(*c.chart, 4, 600.0, 6)}, {}, {}});
      g->field = io::terrainSampleField(g->terrain);
      g->field.uniformTolerance = tolerance;
      g->tin = tin::buildTin(g->field, {});
    }
    const tin::SampleField& field = g->field;
    const tin::Tin& terrainTin = g->tin;
    const double m = c.chart->grid().m();
    const io::LaidRoad laid =
        io::layRoadOnPlanet(strip(), *c.chart, m, {c.a, c.b, c.heading}, tolerance, "road");
    const tin::OverlayResult r =
        tin::overlayRoad(field, terrainTin, laid.road, tin::OverlayMode::kStitch);
    const Place place = placeOn(*c.chart, c.a, c.b, c.heading);
    double off = 0, area = 0;
    for (std::size_t f = 0; f < r.tin.triangles.size(); ++f) {
      if (!r.onRoad[f]) continue;
      std::array<Eigen::Vector2d, 3> q;
      for (int k = 0; k < 3; ++k) {
        q[std::size_t(k)] =
            inRoadPlane(*c.chart, place, r.positions[r.tin.triangles[f][std::size_t(k)]]);
        off = std::max({off, std::abs(q[std::size_t(k)].x()) - kHalfWidth,
                        std::abs(q[std::size_t(k)].y()) - kHalfLength});
      }
      area += 0.5 * std::abs((q[1] - q[0]).x() * (q[2] - q[0]).y() -
                             (q[1] - q[0]).y() * (q[2] - q[0]).x());
    }
    const std::string where = c.chart->name() + " at " + std::to_string(c.a) + ", " +
                              std::to_string(c.b) + " heading " + std::to_string(c.heading);
    EXPECT_EQ(r.report.undrapedEdges, 0u) << where;
    EXPECT_LT(r.report.addedVertexErrorM, 1e-3) << where << ": the vertices stay on the mesh";
    const double ratio = area / (4 * kHalfWidth * kHalfLength);
    if (laid.pieces == 1) {
      // Every vertex on the normal through its own point, every edge on its own plane: the road
      // group covers the footprint, no more and no less.
      ++whole;
      farthestMove = std::max(farthestMove, r.report.drapeMoveM);
      const bool sphere = c.chart == octa || c.chart == latlong;
      EXPECT_LT(off, sphere ? 0.05 : 5.0) << where;
      EXPECT_NEAR(ratio, 1.0, sphere ? 1e-6 : 1e-3) << where;
    } else {
      // Cut at a glued side: its vertices there stay on the side (their twins' places), moved
      // as the mesh moves them, the laid edges' stray at most.
      EXPECT_LT(off, tolerance) << where;
      EXPECT_NEAR(ratio, 1.0, 0.01) << where;
    }
  }
  std::cout << whole << " placements whole, the farthest vertex moved " << farthestMove << " m\n";
  EXPECT_GT(whole, placements / 2);
  // Without the drape those vertices would stand this far from their chart points' normals.
  EXPECT_GT(farthestMove, 1000.0);
}
