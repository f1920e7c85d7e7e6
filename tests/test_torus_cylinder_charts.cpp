// The torus and the cylinder (core/torus_chart.hpp, core/cylinder_chart.hpp): their mappings
// and inverses, the topology they give as data (canonical vertices, twins, gluing), and what
// holds on the octahedral chart holding on them: bounds equal to a full rebuild after edits
// across both seams and at the torus's corner, region growing equal to brute force, crack-free
// tessellations within dist_max, welded meshes of Euler characteristic 0 (the torus closed, the
// cylinder bordered at its ends only), brush edits that keep twins, bounds and undo.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "edit/brush.hpp"
#include "edit/distance_field.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/grid_consistency.hpp"
#include "edit/region_growing.hpp"
#include "io/mesh_export.hpp"
#include "stress_util.hpp"
#include "terrain/error_bounds.hpp"
#include "terrain/error_mesher.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "tin/tin_check.hpp"

using namespace ps;

namespace {

constexpr double kMajor = 4.0e6, kMinor = 1.5e6;        // the torus
constexpr double kTubeRadius = 2.0e6, kLength = 8.0e6;  // the cylinder

std::shared_ptr<const core::Chart> torus(int n) {
  return std::make_shared<core::TorusChart>(core::GridSize(n), kMajor, kMinor);
}
std::shared_ptr<const core::Chart> cylinder(int n) {
  return std::make_shared<core::CylinderChart>(core::GridSize(n), kTubeRadius, kLength);
}

// Rough deterministic relief from each vertex's position (twins are one point bit for bit, so
// they get one height; on the cylinder up() alone would not vary along the axis).
terrain::Terrain bumpy(std::shared_ptr<const core::Chart> chart, std::uint32_t seed,
                       double amplitude) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<std::pair<Eigen::Vector3d, double>> bumps;
  const core::GridSize g = chart->grid();
  const int m = g.m();
  for (int i = 0; i < 30; ++i) {
    const auto p = chart->position(int(rng() % std::uint32_t(m)), int(rng() % std::uint32_t(m)), 0);
    bumps.push_back({p, amplitude * uni(rng)});
  }
  bumps.push_back({chart->position(0, 0, 0), amplitude});  // on the seams' crossing
  std::vector<float> h(g.count());
  for (int v = 0; v <= m; ++v)
    for (int u = 0; u <= m; ++u) {
      const Eigen::Vector3d p = chart->position(u, v, 0) / 1.0e6;
      double x = 0.15 * amplitude * std::sin(7 * p.x() + 1) * std::cos(5 * p.y() - 2) *
                 std::sin(6 * p.z() + 0.5);
      for (const auto& [c, a] : bumps) x += a * std::exp(-(p - c / 1.0e6).squaredNorm() / 0.3);
      h[g.index(u, v)] = float(x);
    }
  return terrain::Terrain(std::move(chart), std::move(h));
}

struct TubeChartCase {
  const char* name;
  std::shared_ptr<const core::Chart> (*make)(int);
};
const std::array<TubeChartCase, 2> kTubeChartCases{TubeChartCase{"torus", torus},
                                                   TubeChartCase{"cylinder", cylinder}};

bool isTorus(const core::Chart& c) {
  return c.name() == "torus";
}

// Every edge of the mesh, after welding by canonical, is used by two triangles in opposite
// directions, but edges along the open ends (both vertices on row 0 or both on row m of a
// chart whose v sides are open), which are used once. "" when so.
std::string conformityDefect(const terrain::Terrain& t, const terrain::Mesh& mesh) {
  const auto side = std::uint64_t(t.grid().side());
  const int m = t.grid().m();
  const bool openEnds = t.chart().gluing().vSides == core::SideGluing::kOpen;
  auto id = [&](std::uint64_t gi) {
    const core::GridPoint p = t.chart().canonical(int(gi % side), int(gi / side));
    return std::int64_t(p.v) * std::int64_t(side) + p.u;
  };
  auto row = [&](std::int64_t x) { return int(x / std::int64_t(side)); };
  std::map<std::pair<std::int64_t, std::int64_t>, int> directed;
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    const std::int64_t a = id(mesh.gridIndex[mesh.indices[3 * k]]),
                       b = id(mesh.gridIndex[mesh.indices[3 * k + 1]]),
                       c = id(mesh.gridIndex[mesh.indices[3 * k + 2]]);
    if (a == b || b == c || a == c) return "degenerate triangle";
    for (auto e : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
      if (++directed[e] > 1) return "directed edge used twice";
  }
  for (const auto& [e, n] : directed) {
    if (directed.count({e.second, e.first})) continue;
    const bool end =
        openEnds && row(e.first) == row(e.second) && (row(e.first) == 0 || row(e.first) == m);
    if (!end)
      return "edge (" + std::to_string(e.first % std::int64_t(side)) + "," +
             std::to_string(row(e.first)) + ")-(" + std::to_string(e.second % std::int64_t(side)) +
             "," + std::to_string(row(e.second)) + ") has no partner";
  }
  return "";
}

tin::MeshTopology topologyOf(const terrain::Mesh& welded) {
  std::vector<std::array<std::uint32_t, 3>> triangles;
  for (std::size_t k = 0; k + 2 < welded.indices.size(); k += 3)
    triangles.push_back({welded.indices[k], welded.indices[k + 1], welded.indices[k + 2]});
  return tin::meshTopology(welded.gridIndex.size(), triangles);
}

// Border edges of a welded mesh that do not lie along an open end.
std::size_t borderEdgesOffTheEnds(const terrain::Terrain& t, const terrain::Mesh& welded) {
  const auto side = std::uint64_t(t.grid().side());
  const int m = t.grid().m();
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (std::size_t k = 0; k + 2 < welded.indices.size(); k += 3)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = welded.indices[k + std::size_t(e)],
                          b = welded.indices[k + std::size_t((e + 1) % 3)];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::size_t off = 0;
  for (const auto& [e, n] : uses) {
    if (n != 1) continue;
    const int va = int(welded.gridIndex[e.first] / side),
              vb = int(welded.gridIndex[e.second] / side);
    if (!(va == vb && (va == 0 || va == m))) ++off;
  }
  return off;
}

}  // namespace

// Every grid vertex lies on the surface (the torus: at the minor radius from the tube's centre
// circle; the cylinder: at its radius from the axis), up() is the outward normal, and the
// inverse gives a point back; random points of the surface go to the grid and back.
TEST(TorusAndCylinder, MapsTheGridOntoTheSurfaceAndBack) {
  for (const TubeChartCase& k : kTubeChartCases) {
    const auto chart = k.make(6);
    const core::Chart& c = *chart;
    const int m = c.grid().m();
    const bool tor = isTorus(c);
    auto surfaceDistance = [&](const Eigen::Vector3d& p) {
      const double rho = std::hypot(p.x(), p.y());
      return tor ? std::hypot(rho - kMajor, p.z()) : rho;
    };
    const double r0 = tor ? kMinor : kTubeRadius;
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        const Eigen::Vector3d p = c.position(u, v, 0), q = c.position(u, v, 1000.0);
        ASSERT_NEAR(surfaceDistance(p), r0, 1e-6) << k.name << " " << u << "," << v;
        ASSERT_NEAR(surfaceDistance(q), r0 + 1000.0, 1e-6);
        ASSERT_LT(((q - p) / 1000.0 - c.up(u, v)).norm(), 1e-9);
        if (!tor) {
          ASSERT_NEAR(p.z(), kLength * (double(v) / m - 0.5), 1e-6);
        }
        const auto back = c.inverse(q);
        ASSERT_TRUE(back);
        ASSERT_LT((c.positionAt(back->x(), back->y(), 0) - p).norm(), 1e-6)
            << k.name << " " << u << "," << v;
      }
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uni(0.0, double(m));
    for (int i = 0; i < 2000; ++i) {
      const double u = uni(rng), v = uni(rng);
      const Eigen::Vector3d p = c.positionAt(u, v, 0);
      const auto uv = c.inverse(p + 500.0 * (c.positionAt(u, v, 1.0) - p));
      ASSERT_TRUE(uv);
      ASSERT_LT((c.positionAt(uv->x(), uv->y(), 0) - p).norm(), 1e-6) << k.name;
    }
    EXPECT_FALSE(c.inverse(Eigen::Vector3d(0, 0, 5.0)));  // on the axis
    EXPECT_EQ(c.sphereRadius(), 0.0);  // no sphere about the origin: no horizon occluder
    EXPECT_EQ(c.heightLimit(), 0.25 * r0);
  }
  const core::TorusChart t(core::GridSize(5), kMajor, kMinor);
  EXPECT_FALSE(t.inverse(Eigen::Vector3d(kMajor, 0, 0)));  // the tube's centre circle
}

TEST(TorusAndCylinder, RefusesRadiiThatAreNoRingTorus) {
  const core::GridSize g(5);
  const double inf = std::numeric_limits<double>::infinity(),
               nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [major, minor] :
       {std::pair{1.0, 1.0}, std::pair{1.0, 2.0}, std::pair{1.0, 0.0}, std::pair{1.0, -0.5},
        std::pair{inf, 1.0}, std::pair{1.0, nan}}) {
    try {
      core::TorusChart t(g, major, minor);
      ADD_FAILURE() << major << " " << minor << " accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("minor"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(std::to_string(minor)), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(core::CylinderChart(g, 0.0, 1.0), core::InputError);
  EXPECT_THROW(core::CylinderChart(g, 1.0, -1.0), core::InputError);
  EXPECT_THROW(core::CylinderChart(g, nan, 1.0), core::InputError);
}

// Twins are one point bit for bit and share one canonical vertex; the torus has m^2 distinct
// points (V - E + F = m^2 - 3 m^2 + 2 m^2 = 0), the cylinder m (m + 1) (an annulus: 0 too).
TEST(TorusAndCylinder, TwinsAreOnePointAndShareTheirCanonicalVertex) {
  for (const TubeChartCase& k : kTubeChartCases) {
    const auto chart = k.make(5);
    const core::Chart& c = *chart;
    const int m = c.grid().m();
    const bool tor = isTorus(c);
    std::set<std::pair<int, int>> canonicals;
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        core::GridPoint t[4];
        const int n = c.twins(u, v, t);
        const bool uSide = u == 0 || u == m, vSide = tor && (v == 0 || v == m);
        ASSERT_EQ(n, (uSide ? 2 : 1) * (vSide ? 2 : 1)) << k.name << " " << u << "," << v;
        ASSERT_EQ(t[0], (core::GridPoint{u, v}));
        const core::GridPoint can = c.canonical(u, v);
        canonicals.insert({can.u, can.v});
        for (int i = 0; i < n; ++i) {
          ASSERT_EQ(c.canonical(t[i].u, t[i].v), can);
          ASSERT_EQ(c.position(t[i].u, t[i].v, 10.0), c.position(u, v, 10.0));  // bit for bit
          ASSERT_EQ(c.up(t[i].u, t[i].v), c.up(u, v));
        }
      }
    const auto mm = std::size_t(m);
    EXPECT_EQ(canonicals.size(), tor ? mm * mm : mm * (mm + 1)) << k.name;
    EXPECT_EQ(c.gluing().uSides, core::SideGluing::kSeam);
    EXPECT_EQ(c.gluing().vSides, tor ? core::SideGluing::kSeam : core::SideGluing::kOpen);
    EXPECT_EQ(c.gluesSidesBeyondSeam(), tor);
    // Beyond the sides the grid goes on at the other end of a seam; an open end clamps.
    EXPECT_EQ(c.continued(-3, 5), (core::GridPoint{m - 3, 5}));
    EXPECT_EQ(c.continued(m + 2, -1), (core::GridPoint{2, tor ? m - 1 : 0}));
    EXPECT_EQ(c.continued(4, m + 3), (core::GridPoint{4, tor ? 3 : m}));
  }
}

// The torus's v -> m - v is its z -> -z bit for bit (gluedImages' midline images rest on it).
TEST(TorusAndCylinder, TheGridsMirrorIsTheTorussMirror) {
  const auto c = torus(6);
  const int m = c->grid().m();
  for (int v = 0; v <= m; ++v)
    for (int u = 0; u <= m; ++u) {
      const Eigen::Vector3d p = c->position(u, v, 7.0), q = c->position(u, m - v, 7.0);
      ASSERT_EQ(p.x(), q.x());
      ASSERT_EQ(p.y(), q.y());
      ASSERT_EQ(p.z(), -q.z());
    }
  // The images of a box at the v seam: itself and its reflection; away from the sides: itself.
  core::GridBox out[4];
  ASSERT_EQ(c->gluedImages({3, 9, 0, 5}, false, out), 2);
  EXPECT_EQ(out[1], (core::GridBox{3, 9, m - 5, m}));
  EXPECT_EQ(c->gluedImages({3, 9, 5, 9}, true, out), 1);
  EXPECT_EQ(c->gluedImages({3, 9, m / 2 - 1, m / 2 + 2}, true, out), 2);
  EXPECT_EQ(c->gluedImages({3, 9, m / 2 - 1, m / 2 + 2}, false, out), 1);
}

// Random edits, across both seams and at the torus's corner (the seams' crossing): the bounds
// updated over the edit's rectangle equal a full rebuild bit for bit.
TEST(TorusAndCylinder, LocalBoundUpdatesEqualAFullRebuildBitForBit) {
  for (const TubeChartCase& k : kTubeChartCases) {
    auto t = bumpy(k.make(7), 5, 4000.0);
    const auto g = t.grid();
    const int m = g.m();
    std::mt19937 rng(17);
    for (int trial = 0; trial < 20; ++trial) {
      int u0 = int(rng() % std::uint32_t(m + 1)), v0 = int(rng() % std::uint32_t(m + 1));
      const int w = 1 + int(rng() % 20), hgt = 1 + int(rng() % 20);
      if (trial % 5 == 0) v0 = 0;                  // on the side v = 0
      if (trial % 5 == 1) v0 = m - hgt;            // on the side v = m
      if (trial % 5 == 2) u0 = -w / 2;             // across the u seam (unwrapped)
      if (trial % 5 == 3) u0 = m - w / 2, v0 = 0;  // at the corner: across both seams
      v0 = std::clamp(v0, 0, m - hgt);
      const terrain::VertexBox region{u0, u0 + w, v0, v0 + hgt};
      auto h = t.mutableHeights();
      const float bump = float(50 + rng() % 400);
      region.forEachColumnRange(g, [&](int a, int b) {
        for (int v = region.vBegin; v <= region.vEnd; ++v)
          for (int u = a; u <= b; ++u) {
            const core::GridPoint c = t.chart().canonical(u, v);
            if (c.u != u || c.v != v) continue;  // each point once
            edit::applyToVertex(t.chart(), h, u, v, h[g.index(u, v)] + bump);
          }
      });
      t.commitEdit(region);
      ASSERT_NO_THROW(terrain::Terrain::validateHeights(t.chart(), t.heights()));
      terrain::ErrorBounds full;
      full.build(t.chart(), t.heights(), terrain::ErrorRule::kHybridExact);
      ASSERT_EQ(full.errorCodes(), t.bounds().errorCodes())
          << k.name << " trial " << trial << " " << region.describe();
      ASSERT_EQ(full.radiusCodes(), t.bounds().radiusCodes()) << k.name << " trial " << trial;
      ASSERT_TRUE(full.lattice() == t.bounds().lattice()) << k.name << " trial " << trial;
    }
    // Twins are one vertex of the surface's bintree: they hold one, combined, pair of codes (a
    // rebuild equal to the update would not show that both skipped the combining).
    const auto& codes = t.bounds().codes();
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        core::GridPoint tw[4];
        const int n = t.chart().twins(u, v, tw);
        for (int i = 1; i < n; ++i) {
          const auto &a = codes[g.index(u, v)], &b = codes[g.index(tw[i].u, tw[i].v)];
          ASSERT_TRUE(a.error == b.error && a.radius == b.radius)
              << k.name << " (" << u << "," << v << ") and (" << tw[i].u << "," << tw[i].v << ")";
        }
      }
  }
}

// Region growing equals brute force (every vertex within the radius in 3D): centres on the
// seams, at the corner, at the torus's inner and outer equators and anywhere; radii from a cell
// to across the hole. Every vertex lies in an image of the dirty box.
TEST(TorusAndCylinder, RegionGrowingEqualsBruteForce) {
  for (const TubeChartCase& k : kTubeChartCases) {
    const auto chart = k.make(7);
    const int m = chart->grid().m();
    edit::DistanceField field(chart);
    edit::RegionGrower grower;
    edit::Region region;
    std::mt19937 rng(23);
    std::vector<core::GridPoint> centres{{0, 0},     {m, m},     {0, 40},           {m, 90},
                                         {70, 0},    {70, m},    {m / 2, m / 2},    {30, m / 4},
                                         {m / 2, 3}, {5, m - 2}, {m - 1, m / 2 + 1}};
    for (int i = 0; i < 10; ++i)
      centres.push_back({int(rng() % std::uint32_t(m + 1)), int(rng() % std::uint32_t(m + 1))});
    const double L = isTorus(*chart) ? kMinor : kTubeRadius;
    std::vector<std::uint8_t> mask;
    for (const core::GridPoint& c : centres) {
      for (double radius : {0.02 * L, 0.3 * L, 1.2 * L, 3.0 * L, 7.0 * L}) {
        field.setCentre(c);
        grower.grow(field, radius, region);
        const std::size_t brute = edit::bruteForceRegion(field, radius, &mask);
        ASSERT_EQ(region.vertexCount(), brute)
            << k.name << " centre " << c.u << "," << c.v << " r " << radius;
        for (int v = 0; v <= m; ++v)
          for (int u = 0; u <= m; ++u)
            ASSERT_EQ(region.contains(u, v), mask[chart->grid().index(u, v)] != 0)
                << k.name << " (" << u << "," << v << ") centre " << c.u << "," << c.v;
        const auto images = terrain::gluedImages(*chart, region.bounds());
        testing::AssertionResult allInImages = testing::AssertionSuccess();  // the first outside
        region.forEachSpan([&](int v, int a, int b) {
          for (int u = a; u <= b && allInImages; ++u) {
            const bool in = std::any_of(images.begin(), images.end(), [&](const auto& r) {
              bool inU = false;
              r.forEachColumnRange(chart->grid(), [&](int x, int y) { inU |= u >= x && u <= y; });
              return inU && v >= r.vBegin && v <= r.vEnd;
            });
            if (!in)
              allInImages = testing::AssertionFailure() << "(" << u << "," << v << ") in no image";
          }
        });
        ASSERT_TRUE(allInImages) << k.name << " centre " << c.u << "," << c.v << " r " << radius
                                 << " box " << region.bounds().describe();
      }
    }
  }
}

// Views at the seams' crossing, on each seam, at the inner equator (the torus seen across the
// hole) and elsewhere: the whole surface's mesh has no crack (welded by canonical; the
// cylinder's ends are its only border), and the culled view's screen error is within dist_max.
TEST(TorusAndCylinder, TessellationsAreCrackFreeAndWithinDistMax) {
  for (const TubeChartCase& k : kTubeChartCases) {
    const auto t = bumpy(k.make(8), 7, 6000.0);
    const core::Chart& c = t.chart();
    const int m = t.grid().m();
    const std::array<core::GridPoint, 5> spots{
        core::GridPoint{0, 0}, {0, m / 3}, {m / 3, m}, {m / 4, m / 2}, {2 * m / 3, m / 5}};
    for (const core::GridPoint& s : spots) {
      const Eigen::Vector3d target = c.position(s.u, s.v, 0), n = c.up(s.u, s.v);
      for (double altitude : {3e6, 3e5}) {
        const auto cam = terrain::Camera::lookAt(target + altitude * n, target, n.unitOrthogonal(),
                                                 320, 240, 60 * M_PI / 180);
        terrain::Tessellator tess;
        terrain::TessellationSettings ts;
        ts.distMaxPx = 2;
        ts.triangleBudget = 0;
        const auto& mesh = tess.tessellate(t, cam, ts);
        ASSERT_GT(mesh.triangleCount(), 20u) << k.name;
        EXPECT_LE(terrain::measureScreenError(t, cam, mesh).maxPx, ts.distMaxPx + 1e-6)
            << k.name << " (" << s.u << "," << s.v << ") at " << altitude;
        ts.cull = false;
        terrain::Tessellator whole;
        EXPECT_EQ(conformityDefect(t, whole.tessellate(t, cam, ts)), "")
            << k.name << " (" << s.u << "," << s.v << ")";
      }
    }
  }
}

// Whole surfaces meshed to an error and welded by the chart: the torus a closed 2-manifold, the
// cylinder a manifold whose border edges all lie on its two ends; both Euler 0. OBJ and PLY
// go through weldMesh: their vertex counts are the welded mesh's.
TEST(TorusAndCylinder, WholeMeshesAreWeldedTorusAndTube) {
  const auto dir = std::filesystem::temp_directory_path() / "ps_torus_cylinder_meshes";
  std::filesystem::create_directories(dir);
  for (const TubeChartCase& k : kTubeChartCases) {
    const auto t = bumpy(k.make(7), 2, 5000.0);
    const bool tor = isTorus(t.chart());
    for (double error : {20000.0, 2000.0}) {
      const terrain::Mesh mesh = terrain::meshToError(t, error);
      EXPECT_LE(terrain::measureTrueError(t, mesh), error);
      const terrain::Mesh welded = io::weldMesh(t, mesh);
      const tin::MeshTopology top = topologyOf(welded);
      EXPECT_EQ(top.nonManifoldEdges, 0u) << k.name << " at " << error;
      EXPECT_EQ(top.degenerate, 0u);
      EXPECT_EQ(top.euler(), 0) << k.name << " at " << error;
      if (tor) {
        EXPECT_EQ(top.borderEdges, 0u) << "torus at " << error;
      } else {
        EXPECT_GT(top.borderEdges, 0u);
        EXPECT_EQ(borderEdgesOffTheEnds(t, welded), 0u) << "cylinder at " << error;
      }
    }
    for (const io::MeshFormat format : {io::MeshFormat::kObj, io::MeshFormat::kPly}) {
      const auto path =
          dir / (std::string(k.name) + (format == io::MeshFormat::kObj ? ".obj" : ".ply"));
      terrain::Mesh raw;
      const io::MeshExportReport rep = io::exportMesh(t, 3000.0, format, path, &raw);
      const terrain::Mesh welded = io::weldMesh(t, raw);
      EXPECT_EQ(rep.vertices, welded.gridIndex.size()) << k.name;
      EXPECT_LT(rep.vertices, raw.gridIndex.size()) << k.name << ": nothing was welded";
      std::ifstream in(path);
      std::string line;
      std::size_t vertices = 0;
      while (std::getline(in, line)) {
        if (format == io::MeshFormat::kObj && line.rfind("v ", 0) == 0) ++vertices;
        if (format == io::MeshFormat::kPly && line.rfind("element vertex ", 0) == 0)
          vertices = std::stoul(line.substr(15));
      }
      EXPECT_EQ(vertices, welded.gridIndex.size()) << k.name << " " << path;
    }
  }
  std::filesystem::remove_all(dir);
}

// Brush strokes anywhere, across both seams and at the torus's corner, through the edit
// pipeline: the bounds equal a full rebuild bit for bit after each, twins stay one height,
// every vertex that changed lies in an image of the reported dirty box, and undo gives the
// heights back bit for bit.
TEST(TorusAndCylinder, BrushEditsKeepBoundsTwinsAndUndo) {
  for (const TubeChartCase& k : kTubeChartCases) {
    auto t = bumpy(k.make(7), 9, 3000.0);
    const core::Chart& c = t.chart();
    const auto g = t.grid();
    const int m = g.m();
    const double L = isTorus(c) ? kMinor : kTubeRadius;
    const std::vector<float> original(t.heights().begin(), t.heights().end());
    edit::EditPipeline pipe(t);
    std::mt19937 rng(31);
    std::vector<core::GridPoint> spots{{0, 0}, {m, m / 2}, {m / 3, m}, {m / 2, m / 2}, {0, 3}};
    for (int i = 0; i < 6; ++i)
      spots.push_back({int(rng() % std::uint32_t(m + 1)), int(rng() % std::uint32_t(m + 1))});
    int edits = 0;
    for (const core::GridPoint& s : spots) {
      const std::vector<float> before(t.heights().begin(), t.heights().end());
      edit::BrushSettings b;
      b.radius = (0.05 + 0.4 * double(rng() % 100) / 100.0) * L;
      b.strength = 1500;
      const auto rep = pipe.apply(edit::GaussianBrush(b), {c.position(s.u, s.v, 0.0), 0.0});
      ++edits;
      ASSERT_GT(rep.modifiedVertices, 0u) << k.name;
      terrain::ErrorBounds full;
      full.build(c, t.heights(), terrain::ErrorRule::kHybridExact);
      ASSERT_EQ(full.errorCodes(), t.bounds().errorCodes()) << k.name << " " << s.u << "," << s.v;
      ASSERT_EQ(full.radiusCodes(), t.bounds().radiusCodes()) << k.name;
      ASSERT_NO_THROW(terrain::Terrain::validateHeights(c, t.heights()));
      const auto images = terrain::gluedImages(c, rep.dirty);
      for (int v = 0; v <= m; ++v)
        for (int u = 0; u <= m; ++u) {
          if (before[g.index(u, v)] == t.heights()[g.index(u, v)]) continue;
          const bool in = std::any_of(images.begin(), images.end(), [&](const auto& r) {
            bool inU = false;
            r.forEachColumnRange(g, [&](int x, int y) { inU |= u >= x && u <= y; });
            return inU && v >= r.vBegin && v <= r.vEnd;
          });
          ASSERT_TRUE(in) << k.name << " (" << u << "," << v << ") changed outside the images of "
                          << rep.dirty.describe();
        }
    }
    for (int i = 0; i < edits; ++i) pipe.undo();
    EXPECT_TRUE(std::equal(original.begin(), original.end(), t.heights().begin())) << k.name;
    terrain::ErrorBounds full;
    full.build(c, t.heights(), terrain::ErrorRule::kHybridExact);
    EXPECT_EQ(full.errorCodes(), t.bounds().errorCodes()) << k.name;
  }
}

// Random actions, as the stress suite runs them on lat-long and the octahedral chart: brush
// stamps and strokes with radii from a hundredth to three times the tube's radius, at random
// vertices biased to the seams and the torus's corner, raise, lower and set, undo and redo, and
// bad input (refused, nothing changed). After each action every twin holds its point's height,
// finite and within the limit; every 23 the bounds equal a full rebuild bit for bit; every 61 a
// tessellation from a random view is crack-free; undoing everything gives back the first
// heights bit for bit.
TEST(StressTubeEdits, RandomBrushActionsKeepEveryInvariant) {
  const int actions = (testkit::underAsan() ? 60 : 240) * testkit::stressScale();
  for (const TubeChartCase& k : kTubeChartCases) {
    auto t = bumpy(k.make(6), 17, 3000.0);
    const core::Chart& c = t.chart();
    const int m = t.grid().m();
    const double tube = isTorus(c) ? kMinor : kTubeRadius;
    const double extent = isTorus(c) ? kMajor + kMinor : std::hypot(kTubeRadius, 0.5 * kLength);
    const std::vector<float> original(t.heights().begin(), t.heights().end());
    edit::EditPipeline pipe(t);
    std::mt19937 rng(20261127);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    terrain::Tessellator tess;
    for (int i = 0; i < actions; ++i) {
      edit::BrushSettings b;
      b.radius = tube * std::exp(std::log(0.01) + unit(rng) * std::log(300.0));
      b.sigma = (rng() & 1) ? 0.17 : 0.75;
      b.mode = edit::BrushMode(rng() % 3);
      b.strength = 100.0 + 2400.0 * unit(rng);
      b.target = 600.0 * (unit(rng) - 0.5);
      const edit::GaussianBrush brush(b);
      const core::GridPoint s = edittest::randomCentre(rng, m);
      const Eigen::Vector3d p = c.position(s.u, s.v, t.height(s.u, s.v));
      const unsigned kind = rng() % 10;
      std::string what = std::string(k.name) + " action " + std::to_string(i) + " at (" +
                         std::to_string(s.u) + "," + std::to_string(s.v) + ") r " +
                         std::to_string(b.radius) + ": ";
      if (kind < 4) {
        what += "stamp";
        pipe.apply(brush, {p, 0.0});
      } else if (kind < 7) {
        what += "stroke";
        pipe.beginStroke(brush, {p, 0.0});
        Eigen::Vector3d q = p;
        for (int step = 0; step < 4; ++step) {
          // Small steps in any direction (onto the surface's nearest vertex), now and then a jump.
          q += (rng() % 5 == 0 ? extent : b.radius) * Eigen::Vector3d::Random();
          pipe.moveTo({q, 0.05});
        }
        pipe.endStroke();
      } else if (kind < 9) {
        what += kind == 7 ? "undo" : "redo";
        if (kind == 7 && pipe.journal().undoCount() > 0) pipe.undo();
        if (kind == 8 && pipe.journal().redoCount() > 0) pipe.redo();
      } else {
        what += "bad input";
        const std::vector<float> before(t.heights().begin(), t.heights().end());
        edit::BrushSettings bad = b;
        bad.radius = std::numeric_limits<double>::quiet_NaN();
        EXPECT_THROW(pipe.apply(edit::GaussianBrush(bad), {p, 0.0}), core::InputError) << what;
        const Eigen::Vector3d nowhere(std::numeric_limits<double>::infinity(), 0, 0);
        EXPECT_THROW(pipe.apply(brush, {nowhere, 0.0}), core::InputError) << what;
        ASSERT_TRUE(std::equal(before.begin(), before.end(), t.heights().begin())) << what;
      }
      ASSERT_TRUE(edittest::consistentHeights(t)) << what;
      if (i % 23 == 0) {
        ASSERT_TRUE(edittest::boundsEqualFullRebuild(t)) << what;
      }
      if (i % 61 == 0) {
        const Eigen::Vector3d dir = Eigen::Vector3d::Random().normalized();
        const auto cam = terrain::Camera::lookAt((1.5 + 8.0 * unit(rng)) * extent * dir,
                                                 Eigen::Vector3d::Zero(), {0, 0, 1}, 320, 240, 1.0);
        terrain::TessellationSettings ts;
        ts.cull = false;
        ts.triangleBudget = 0;
        ts.distMaxPx = 0.5 + 8.0 * unit(rng);
        ASSERT_EQ(conformityDefect(t, tess.tessellate(t, cam, ts)), "") << what;
      }
    }
    while (pipe.journal().undoCount() > 0) pipe.undo();
    EXPECT_TRUE(std::equal(original.begin(), original.end(), t.heights().begin())) << k.name;
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t)) << k.name;
  }
}
