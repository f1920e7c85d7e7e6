// Roads stitched and stenciled into a terrain TIN (tin/overlay): the surface kept (stitch) or
// the road's kept and the ground within its error (stencil), every input edge present, the
// mesh a manifold; refusals of roads that are not proper meshes; the OBJ road reader.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "core/input_error.hpp"
#include "fresh_dir.hpp"
#include "io/obj_triangles.hpp"
#include "io/overlay_export.hpp"
#include "io/planet_file.hpp"
#include "stress_util.hpp"
#include "test_terrains.hpp"
#include "tin/overlay.hpp"
#include "tin/strip.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_locator.hpp"
#include "tin/triangle_error.hpp"

namespace ps::tin {
namespace {

struct Scene {
  int w = 61, h = 47;
  std::vector<float> heights;
  SampleField field;
  Tin terrain;
};

Scene makeScene(double tolerance, std::uint32_t seed) {
  Scene s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0, 1);
  s.heights.resize(std::size_t(s.w) * std::size_t(s.h));
  for (int j = 0; j < s.h; ++j)
    for (int i = 0; i < s.w; ++i)
      s.heights[std::size_t(j * s.w + i)] =
          float(30 * std::sin(0.15 * i) * std::cos(0.2 * j) + 10 * std::sin(0.05 * i * j / 7.0) +
                0.5 * uni(rng));
  s.field.width = s.w;
  s.field.height = s.h;
  s.field.heights = s.heights;
  s.field.dx = 2.0;
  s.field.dy = 2.0;
  s.field.uniformTolerance = tolerance;
  s.terrain = buildTin(s.field, {});
  return s;
}

// A road: a strip of quads (two triangles each) along a curve, `width` lattice units wide.
Road roadAlong(const std::vector<Eigen::Vector2d>& centre, double width, double lift,
               const SampleField& field) {
  Road t;
  for (std::size_t k = 0; k < centre.size(); ++k) {
    const Eigen::Vector2d d =
        (centre[std::min(k + 1, centre.size() - 1)] - centre[k == 0 ? 0 : k - 1]).normalized();
    const Eigen::Vector2d n(-d.y(), d.x());
    for (const double side : {-0.5, 0.5}) {
      const Eigen::Vector2d p = centre[k] + side * width * n;
      t.xy.push_back(p);
      t.h.push_back(field.heightAt(std::clamp(p.x(), 0.0, double(field.width - 1)),
                                   std::clamp(p.y(), 0.0, double(field.height - 1))) +
                    lift);
    }
    if (k > 0) {
      const auto a = std::uint32_t(2 * k - 2), b = a + 1, c = a + 2, d2 = a + 3;
      t.triangles.push_back({a, c, d2});
      t.triangles.push_back({a, d2, b});
    }
  }
  return t;
}

std::vector<Eigen::Vector2d> curve(double x0, double x1, double y, int n) {
  std::vector<Eigen::Vector2d> c;
  for (int k = 0; k < n; ++k) {
    const double x = x0 + (x1 - x0) * k / (n - 1);
    c.emplace_back(x, y + 6 * std::sin(0.2 * x) + 0.37);
  }
  return c;
}

// The total length of `edges` lying on the segment ab (collinear and inside it).
double coveredLength(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Tin& tin) {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  double covered = 0;
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  for (const auto& t : tin.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = t[std::size_t(k)], q = t[std::size_t((k + 1) % 3)];
      if (!seen.insert({std::min(p, q), std::max(p, q)}).second) continue;
      const Eigen::Vector2d &u = tin.xy[p], &v = tin.xy[q];
      auto offLine = [&](const Eigen::Vector2d& x) {
        return std::abs(d.x() * (x - a).y() - d.y() * (x - a).x()) / len;
      };
      auto along = [&](const Eigen::Vector2d& x) { return (x - a).dot(d) / len; };
      if (offLine(u) > 1e-7 || offLine(v) > 1e-7) continue;
      if (std::min(along(u), along(v)) < -1e-7 || std::max(along(u), along(v)) > len + 1e-7)
        continue;
      covered += (v - u).norm();
    }
  return covered;
}

// An overlay's summary of a whole planet: one closed surface (Euler 2, every edge between two
// triangles).
void expectOneClosedSurface(const nlohmann::json& s) {
  EXPECT_EQ(s["euler"], 2) << s.dump();
  EXPECT_EQ(s["border_edges"], 0) << s.dump();
  EXPECT_EQ(s["non_manifold_edges"], 0) << s.dump();
}

double heightOn(const Tin& tin, const TinLocator& where, const Eigen::Vector2d& p) {
  double h = NAN;
  where.visit(p, [&](const TinLocator::Hit& hit) {
    if (std::isnan(h)) {
      const auto& t = tin.triangles[hit.triangle];
      h = hit.l0 * tin.h[t[0]] + hit.l1 * tin.h[t[1]] + hit.l2 * tin.h[t[2]];
    }
  });
  return h;
}

TEST(TinOverlay, StitchingKeepsTheSurfaceAndEveryEdgeOfBoth) {
  const Scene s = makeScene(2.0, 3);
  const Road road = roadAlong(curve(4.3, 55.1, 20.2, 14), 3.0, 0.0, s.field);
  const OverlayResult r = overlayRoad(s.field, s.terrain, road, OverlayMode::kStitch);
  EXPECT_GT(r.report.crossingVertices, 20u);
  EXPECT_LE(r.report.addedVertexErrorM, 1e-9);
  // The surface is the terrain's: every sample at the same height on both, and the result's
  // error against the samples is the terrain TIN's.
  const TinLocator before(s.terrain.xy, s.terrain.triangles, s.w, s.h);
  const TinLocator after(r.tin.xy, r.tin.triangles, s.w, s.h);
  for (int j = 0; j < s.h; ++j)
    for (int i = 0; i < s.w; ++i)
      ASSERT_NEAR(heightOn(r.tin, after, {i, j}), heightOn(s.terrain, before, {i, j}), 1e-9);
  for (std::size_t v = 0; v < r.tin.xy.size(); ++v)
    EXPECT_NEAR(heightOn(s.terrain, before, r.tin.xy[v]), r.tin.h[v], 1e-9) << "vertex " << v;
  // Every edge of both meshes is a union of the result's edges.
  for (const auto& t : s.terrain.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto &a = s.terrain.xy[t[std::size_t(k)]],
                 &b = s.terrain.xy[t[std::size_t((k + 1) % 3)]];
      ASSERT_NEAR(coveredLength(a, b, r.tin), (b - a).norm(), 1e-6);
    }
  for (const auto& t : road.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto &a = road.xy[t[std::size_t(k)]], &b = road.xy[t[std::size_t((k + 1) % 3)]];
      ASSERT_NEAR(coveredLength(a, b, r.tin), (b - a).norm(), 1e-6);
    }
  const MeshTopology top = meshTopology(r.tin.xy.size(), r.tin.triangles);
  EXPECT_EQ(top.nonManifoldEdges, 0u);
  EXPECT_EQ(top.degenerate, 0u);
  EXPECT_EQ(top.euler(), 1);
  std::size_t onRoad = 0;
  for (const auto f : r.onRoad) onRoad += f;
  EXPECT_GE(onRoad, road.triangles.size());
}

TEST(TinOverlay, StencilingKeepsTheRoadAndTheGroundWithinItsError) {
  const Scene s = makeScene(0.8, 5);
  const Road road = roadAlong(curve(6.1, 50.3, 22.6, 12), 4.0, 2.5, s.field);  // a raised road
  const OverlayResult r = overlayRoad(s.field, s.terrain, road, OverlayMode::kStencil);
  EXPECT_GT(r.report.removedTerrainVertices, 0u);
  EXPECT_LE(r.report.footprintErrorM, 1e-9);
  EXPECT_LE(r.report.outsideErrorRatio, 1.0 + kCheckSlack);
  // The road's vertices are in the result with the road's heights.
  for (std::size_t v = 0; v < road.xy.size(); ++v) {
    bool found = false;
    for (std::size_t w = 0; w < r.tin.xy.size(); ++w)
      if ((r.tin.xy[w] - road.xy[v]).norm() < 1e-12) {
        found = true;
        EXPECT_DOUBLE_EQ(r.tin.h[w], road.h[v]);
      }
    EXPECT_TRUE(found) << "road vertex " << v;
  }
  // No terrain sample vertex is left strictly inside the footprint.
  const TinLocator footprint(road.xy, road.triangles, s.w, s.h);
  for (std::size_t w = 0; w < r.tin.xy.size(); ++w) {
    const Eigen::Vector2d& p = r.tin.xy[w];
    const bool roadVertex = std::any_of(road.xy.begin(), road.xy.end(),
                                        [&](const auto& q) { return (q - p).norm() < 1e-12; });
    if (!roadVertex) {
      EXPECT_FALSE(footprint.contains(p, -1e-9)) << "vertex " << w;
    }
  }
  const MeshTopology top = meshTopology(r.tin.xy.size(), r.tin.triangles);
  EXPECT_EQ(top.nonManifoldEdges, 0u);
  EXPECT_EQ(top.euler(), 1);
}

TEST(TinOverlay, ARoadLeavingTheTerrainIsClippedAtItsBorder) {
  const Scene s = makeScene(1.0, 8);
  const Road road = roadAlong(curve(-10.0, 30.0, 10.0, 9), 3.0, 0.0, s.field);
  for (const OverlayMode mode : {OverlayMode::kStitch, OverlayMode::kStencil}) {
    const OverlayResult r = overlayRoad(s.field, s.terrain, road, mode);
    EXPECT_GT(r.report.clippedRoadTriangles, 0u);
    for (const auto& p : r.tin.xy) {
      EXPECT_GE(p.x(), 0.0);
      EXPECT_GE(p.y(), 0.0);
    }
    const MeshTopology top = meshTopology(r.tin.xy.size(), r.tin.triangles);
    EXPECT_EQ(top.nonManifoldEdges, 0u);
    EXPECT_EQ(top.euler(), 1);
  }
}

TEST(TinOverlay, RefusesRoadsThatAreNotProperMeshes) {
  const Scene s = makeScene(2.0, 1);
  auto expectRefused = [&](const Road& t, const std::string& expected) {
    try {
      overlayRoad(s.field, s.terrain, t, OverlayMode::kStitch);
      ADD_FAILURE() << "accepted; expected: " << expected;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  Road bowTie;  // two triangles whose edges cross
  bowTie.xy = {{10, 10}, {20, 10}, {15, 20}, {10, 16}, {20, 16}, {15, 6}};
  bowTie.h.assign(6, 0.0);
  bowTie.triangles = {{0, 1, 2}, {3, 5, 4}};
  expectRefused(bowTie, "crosses itself");
  Road twice;
  twice.xy = {{10, 10}, {20, 10}, {15, 20}};
  twice.h.assign(3, 0.0);
  twice.triangles = {{0, 1, 2}, {0, 1, 2}};
  expectRefused(twice, "overlaps itself");
  Road flat;
  flat.xy = {{10, 10}, {20, 10}, {30, 10}};
  flat.h.assign(3, 0.0);
  flat.triangles = {{0, 1, 2}};
  expectRefused(flat, "degenerate");
  Road away = twice;
  away.triangles = {{0, 1, 2}};
  for (auto& p : away.xy) p += Eigen::Vector2d(500, 500);
  expectRefused(away, "wholly outside");
}

TEST(TinOverlay, AJitteryStrokeThatDoublesBackStillMakesAProperStrip) {
  const Scene s = makeScene(2.0, 4);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> jitter(-1.5, 1.5);
  std::vector<Eigen::Vector2d> path;  // out along a curve, a scrub back and forth, on again
  for (int k = 0; k <= 60; ++k) {
    const double x = 5 + 0.8 * (k < 30 ? k : k < 40 ? 30 - (k - 30) : k - 20);
    const double back = k > 30 && k < 40 ? 7.0 : 0.0;  // the scrub back runs beside the path
    path.emplace_back(x + jitter(rng), 20 + 8 * std::sin(0.1 * x) + back + jitter(rng));
  }
  const Strip strip = stripAlong(path, 3.0);
  EXPECT_LT(strip.xy.size(), path.size()) << "the jitter is simplified away";
  Road road{strip.xy, std::vector<double>(strip.xy.size(), 0.0), strip.triangles};
  EXPECT_NO_THROW(overlayRoad(s.field, s.terrain, road, OverlayMode::kStitch));
  EXPECT_THROW(stripAlong({{1, 1}, {1, 1}}, 2.0), core::InputError);
  EXPECT_THROW(stripAlong(path, 0.0), core::InputError);
  // Out to a point and back to the last, as a stroke snapped to grid vertices jitters: once the
  // turn is dropped the point before it comes twice in a row, which made a strip of no width
  // there (a degenerate triangle, refused by the overlay).
  for (const auto& jittery :
       {std::vector<Eigen::Vector2d>{{0, 0}, {0, 5}, {0, 0}, {10, 0}, {20, 1}},
        std::vector<Eigen::Vector2d>{{0, 0}, {10, 0}, {10, 5}, {10, 0}}}) {
    const Strip s2 = stripAlong(jittery, 2.0);
    for (const auto& t : s2.triangles) {
      const Eigen::Vector2d a = s2.xy[t[0]], b = s2.xy[t[1]], c = s2.xy[t[2]];
      EXPECT_GT(std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x()), 1e-6);
    }
  }
}

TEST(TinOverlay, ObjRoadsAreReadOrRefusedWithTheLine) {
  const io::ObjTriangles ok = io::parseObjTriangles(
      "# road\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\ng road\nf 1/1/1 2/2/1 3//1\nf -4 -2 "
      "-1\n",
      "road.obj");
  ASSERT_EQ(ok.triangles.size(), 2u);
  EXPECT_EQ(ok.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  auto refused = [](const std::string& text, const std::string& expected) {
    try {
      io::parseObjTriangles(text, "t.obj");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "t.obj:5: a face with 4 corners");
  refused("v 0 0 0\nv 1 0 x\n", "t.obj:2: 'x' is not a finite number");
  refused("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "t.obj:3: vertex index 3 is out of range");
  refused("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 1 2\n", "repeats a vertex");
  refused("v 0 0 0\n", "no triangles");
  refused("v 0 0 0\nv 1 1 1\nl 1 2\n", "not a triangle mesh");
}

TEST(TinOverlay, APlanetKeepsItsClosedSurfaceWithARoadStitchedIn) {
  const auto dir = testkit::freshDir("tin_overlay_planet");
  const terrain::Terrain t = testkit::bumpyTerrain(6, 2, 20000.0);
  io::savePlanet(t, dir / "p.planet");
  // A 300 km x 40 km road.
  std::ofstream(dir / "road.obj") << "v -150000 -20000 0\nv 150000 -20000 0\nv 150000 20000 0\n"
                                     "v -150000 20000 0\nf 1 2 3\nf 1 3 4\n";
  for (const auto mode : {OverlayMode::kStitch, OverlayMode::kStencil}) {
    io::OverlayOptions o;
    o.mode = mode;
    o.errorM = 2000.0;
    o.at = std::array<double, 3>{30.0, 45.0, 20.0};
    std::vector<std::string> notes;
    const nlohmann::json s =
        io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj",
                             dir / "out.obj", io::ExportFormat::kObj, o, notes);
    expectOneClosedSurface(s);
    EXPECT_GT(s["road_group_triangles"].get<int>(), 0);
  }
  io::OverlayOptions o;
  o.errorM = 2000.0;
  std::vector<std::string> notes;
  EXPECT_THROW(io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj",
                                    dir / "x.obj", io::ExportFormat::kObj, o, notes),
               core::InputError)
      << "a planet needs --at";
  // Across the seam (since 2026-12-07; refused before): laid in the grid (a stencil, or a stitch
  // asked to go there), a piece on either side of it; stitched in the road's plane, where there is
  // no seam, one. One surface either way.
  o.at = std::array<double, 3>{10.0, 179.9, 0.0};
  for (const int variant : {0, 1, 2}) {
    o.mode = variant == 0 ? OverlayMode::kStencil : OverlayMode::kStitch;
    o.stitchInGrid = variant == 2;
    const nlohmann::json seam =
        io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj",
                             dir / "seam.obj", io::ExportFormat::kObj, o, notes);
    SCOPED_TRACE(seam.dump());
    expectOneClosedSurface(seam);
    EXPECT_EQ(seam["road_pieces"], variant == 1 ? 1 : 2);
    EXPECT_LE(seam["road_stray_m"].get<double>(), 2000.0);
    if (variant > 0) {
      EXPECT_EQ(seam["stitched_in"], variant == 1 ? "road plane" : "grid");
    }
  }
  // Stitched over a pole in the grid the surface would fold (a grid row is one point): refused,
  // naming the ways that work.
  o.at = std::array<double, 3>{90.0, 30.0, 0.0};
  try {
    io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj", dir / "x.obj",
                         io::ExportFormat::kObj, o, notes);
    ADD_FAILURE() << "stitched over the pole in the grid";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--mode stencil"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("own plane"), std::string::npos) << e.what();
  }
  o.stitchInGrid = false;
  // Beside a pole and over it (since 2026-12-07; refused before: there a grid row is one point):
  // one closed surface, the pole one vertex. Over it, stenciled (the road's fan round the pole
  // spread along the pole's row) and stitched (since 2026-12-08 in the road's own plane, as every
  // stitch on a sphere: tin/plane_stitch.hpp; refused before).
  for (const auto& at :
       {std::array<double, 3>{89.0, 0.0, 0.0}, std::array<double, 3>{90.0, 30.0, 0.0},
        std::array<double, 3>{-89.9, 180.0, 75.0}}) {
    for (const auto mode : {OverlayMode::kStencil, OverlayMode::kStitch}) {
      o.mode = mode;
      o.at = at;
      SCOPED_TRACE(std::to_string(at[0]) + ", " + std::to_string(at[1]) +
                   (mode == OverlayMode::kStitch ? " stitch" : " stencil"));
      const bool over = at[0] != 89.0;
      const nlohmann::json pole =
          io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj",
                               dir / "pole.obj", io::ExportFormat::kObj, o, notes);
      EXPECT_EQ(pole["road_holds_pole"], over) << pole.dump();
      if (mode == OverlayMode::kStitch) {
        EXPECT_EQ(pole["stitched_in"], "road plane");
        EXPECT_LT(pole["added_vertex_error_m"].get<double>(), 1e-6);
      }
      expectOneClosedSurface(pole);
      EXPECT_LE(pole["road_stray_m"].get<double>(), 2000.0);
      EXPECT_GT(pole["road_group_triangles"].get<int>(), 0);
    }
  }
}

// Roads over and beside lat-long's poles at random places and headings (refused until
// 2026-12-07): one closed surface each time, stenciled and stitched (stitched in the road's own
// plane since 2026-12-08; one that holds the pole was refused by name before). Stitched, a road
// vertex whose grid point lies in a terrain triangle with two corners on the pole's row (no area on
// the surface) is draped onto the triangle its point lies on; blended there it lay on the
// triangle's one line, and the surface folded (Euler 3, a non-manifold edge, at 89 N).
TEST(TinOverlay, RoadsOverAndBesideLatLongsPolesKeepTheSurfaceClosed) {
  const auto dir = testkit::freshDir("tin_overlay_poles");
  io::savePlanet(testkit::bumpyTerrain(6, 2, 20000.0), dir / "p.planet");
  std::ofstream(dir / "road.obj") << "v -150000 -20000 0\nv 150000 -20000 0\nv 150000 20000 0\n"
                                     "v -150000 20000 0\nf 1 2 3\nf 1 3 4\n";
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int trials = testkit::underAsan() ? 4 : 12;
  int over = 0;
  for (int trial = 0; trial < trials; ++trial) {
    // Half within 0.15 degrees of a pole (16.7 km: inside the 40 km wide road at any heading),
    // half within 2 degrees.
    const double off = trial % 4 < 2 ? 0.15 * unit(rng) : 2 * unit(rng);
    const double lat = (trial % 2 ? 1 : -1) * (90 - off), lon = 360 * unit(rng) - 180;
    const double heading = 360 * unit(rng);
    for (const auto mode : {OverlayMode::kStencil, OverlayMode::kStitch}) {
      io::OverlayOptions o;
      o.mode = mode;
      o.errorM = 2000.0;
      o.at = std::array<double, 3>{lat, lon, heading};
      std::vector<std::string> notes;
      SCOPED_TRACE(std::to_string(lat) + ", " + std::to_string(lon) + " heading " +
                   std::to_string(heading) +
                   (mode == OverlayMode::kStitch ? " stitch" : " stencil"));
      const nlohmann::json s =
          io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj",
                               dir / "out.obj", io::ExportFormat::kObj, o, notes);
      expectOneClosedSurface(s);
      EXPECT_LE(s["road_stray_m"].get<double>(), 2000.0);
      EXPECT_GT(s["road_group_triangles"].get<int>(), 0);
      const bool holds = s["road_holds_pole"].get<bool>();
      if (mode == OverlayMode::kStitch) {
        EXPECT_EQ(s["stitched_in"], "road plane");
      }
      if (off < 0.15) {
        EXPECT_TRUE(holds);
      }
      over += holds && mode == OverlayMode::kStitch;
    }
  }
  EXPECT_GE(over, trials / 2);
}

// A road whose vertices lie exactly on a glued side (a strip from `road` starts at its place:
// x = 0 there), the rest of it on one side: before 2026-12-07 the other side got no twins of
// those vertices and the welded surface stayed open along them (4-6 border edges).
TEST(TinOverlay, ARoadTouchingAGluedSideKeepsTheSurfaceClosed) {
  const auto dir = testkit::freshDir("tin_overlay_side");
  // 150 km east of its place, 40 km wide: its first two vertices on the place's meridian.
  std::ofstream(dir / "road.obj") << "v 0 -20000 0\nv 150000 -20000 0\nv 150000 20000 0\n"
                                     "v 0 20000 0\nf 1 2 3\nf 1 3 4\n";
  struct Case {
    const char* what;
    terrain::Terrain planet;
    std::array<double, 3> at;
  };
  const std::vector<Case> cases{
      {"lat-long's seam", testkit::bumpyTerrain(6, 2, 20000.0), {10.0, 180.0, 0.0}},
      {"an octahedral fold", testkit::bumpyOctahedralTerrain(6, 2, 20000.0), {-30.0, 0.0, 0.0}},
      {"another octahedral fold",
       testkit::bumpyOctahedralTerrain(6, 2, 20000.0),
       {-40.0, 90.0, 0.0}},
      {"the octahedral south pole's fold",
       testkit::bumpyOctahedralTerrain(6, 2, 20000.0),
       {-60.0, -180.0, 0.0}}};
  for (const Case& c : cases) {
    io::savePlanet(c.planet, dir / "p.planet");
    for (const auto mode : {OverlayMode::kStitch, OverlayMode::kStencil}) {
      io::OverlayOptions o;
      o.mode = mode;
      o.errorM = 2000.0;
      o.at = c.at;
      std::vector<std::string> notes;
      const nlohmann::json s =
          io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj",
                               dir / "out.obj", io::ExportFormat::kObj, o, notes);
      SCOPED_TRACE(std::string(c.what) + (mode == OverlayMode::kStitch ? ", stitch" : ", stencil"));
      expectOneClosedSurface(s);
      EXPECT_GT(s["road_group_triangles"].get<int>(), 0);
    }
  }
}

// Where the terrain's TIN is not seen one to one from the planet's centre a stitch goes in the
// grid, with a note saying so: here a TIN so coarse (a bare octahedral planet at an error of
// 5,000 km: the grid's cone points and their neighbours, little else) that no triangle about the
// road faces its plane within 60 degrees. (A TIN triangle seen edge-on, three corners on one great
// circle, did it at the end of an octahedral fold until 2026-12-08: a 1025^2 Mars at 50 m had one
// at 0 N 180 E; the cone points' constrained edges,
// `TinExport.AnOctahedralConePointWeldsIntoNoFlap`, took those triangles away.)
TEST(TinOverlay, AStitchTheRoadsPlaneCannotSeeGoesInTheGrid) {
  const auto dir = testkit::freshDir("tin_overlay_unseen");
  std::ofstream(dir / "road.obj") << "v -150000 -20000 0\nv 150000 -20000 0\nv 150000 20000 0\n"
                                     "v -150000 20000 0\nf 1 2 3\nf 1 3 4\n";
  const auto chart = testkit::octahedralChart(5);
  io::savePlanet(terrain::Terrain(chart, std::vector<float>(chart->grid().count(), 0.0f)),
                 dir / "p.planet");
  io::OverlayOptions o;
  o.errorM = 5.0e6;
  o.at = std::array<double, 3>{20.0, 30.0, 0.0};
  std::vector<std::string> notes;
  const nlohmann::json s =
      io::overlayFromFiles(dir / "p.planet", io::ImportOptions{}, dir / "road.obj", dir / "out.obj",
                           io::ExportFormat::kObj, o, notes);
  SCOPED_TRACE(s.dump());
  expectOneClosedSurface(s);
  EXPECT_GT(s["road_group_triangles"].get<int>(), 0);
  EXPECT_EQ(s["stitched_in"], "grid");
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("grid, not in the road's plane"), std::string::npos) << notes[0];
}

}  // namespace
}  // namespace ps::tin
