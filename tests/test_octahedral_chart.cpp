// The octahedral chart (core/octahedral_chart.hpp): its mapping and its inverse, the topology it
// gives as data (canonical vertices, twins), and what holds for lat-long holding on it: nested
// bounds equal to a full rebuild after random edits (across the folds too), crack-free
// tessellations within dist_max, and welded meshes of Euler characteristic 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "core/octahedral_chart.hpp"
#include "edit/brush.hpp"
#include "edit/distance_field.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/grid_consistency.hpp"
#include "edit/region_growing.hpp"
#include "io/mesh_export.hpp"
#include "mesh_checks.hpp"
#include "terrain/error_bounds.hpp"
#include "terrain/error_mesher.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"
#include "tin/tin_check.hpp"

using namespace ps;
using Mapping = core::OctahedralChart::Mapping;

namespace {

using testkit::kOctahedralMappings;

}  // namespace

// The centre is the north pole, the corners the south pole, the sides' midpoints the equator;
// every grid vertex lands on the unit sphere and the inverse gives its grid coordinates back.
TEST(OctahedralChart, MapsTheSquareOntoTheSphereAndBack) {
  for (const Mapping mapping : kOctahedralMappings) {
    const core::OctahedralChart c(core::GridSize(6), 1000.0, mapping);
    const int m = c.grid().m();
    EXPECT_LT((c.up(m / 2, m / 2) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
    for (const auto& [u, v] : {std::pair{0, 0}, std::pair{m, 0}, std::pair{0, m}, std::pair{m, m}})
      EXPECT_LT((c.up(u, v) + Eigen::Vector3d::UnitZ()).norm(), 1e-15) << u << "," << v;
    EXPECT_LT((c.up(m, m / 2) - Eigen::Vector3d::UnitX()).norm(), 1e-15);
    EXPECT_LT((c.up(m / 2, m) - Eigen::Vector3d::UnitY()).norm(), 1e-15);
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        const Eigen::Vector3d p = c.position(u, v, 0);
        ASSERT_NEAR(p.norm(), 1000.0, 1e-9);
        const auto back = c.inverse(p);
        ASSERT_TRUE(back);
        // On a folded side the inverse may give the twin's coordinates: the same point.
        const Eigen::Vector3d again = c.positionAt(back->x(), back->y(), 0);
        ASSERT_LT((again - p).norm(), 1e-6) << u << "," << v;
      }
    // Random points of the sphere: inverse, then forward, lands on the same point.
    std::mt19937 rng(3);
    std::normal_distribution<double> n01;
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector3d d = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized();
      const auto uv = c.inverse(3 * d);
      ASSERT_TRUE(uv);
      ASSERT_LT((c.positionAt(uv->x(), uv->y(), 0) - 1000.0 * d).norm(), 1e-7) << d.transpose();
    }
    EXPECT_FALSE(c.inverse(Eigen::Vector3d::Zero()));
  }
}

// The sides fold onto themselves: twins are one point bit for bit, share one canonical
// vertex, and every vertex of the grid that is not on a side is its own.
TEST(OctahedralChart, TwinsAreOnePointAndShareTheirCanonicalVertex) {
  for (const Mapping mapping : kOctahedralMappings) {
    const core::OctahedralChart c(core::GridSize(5), 6.4e6, mapping);
    const int m = c.grid().m();
    std::set<std::pair<int, int>> canonicals;
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        core::GridPoint t[4];
        const int n = c.twins(u, v, t);
        const bool side = u == 0 || u == m || v == 0 || v == m;
        const bool corner = (u == 0 || u == m) && (v == 0 || v == m);
        const bool midpoint = side && !corner && (2 * u == m || 2 * v == m);
        ASSERT_EQ(n, corner ? 4 : (side && !midpoint ? 2 : 1)) << u << "," << v;
        const core::GridPoint k = c.canonical(u, v);
        canonicals.insert({k.u, k.v});
        for (int i = 0; i < n; ++i) {
          ASSERT_EQ(c.canonical(t[i].u, t[i].v), k);
          ASSERT_EQ(c.position(t[i].u, t[i].v, 10.0), c.position(u, v, 10.0));  // bit for bit
        }
      }
    // Points: (m - 1)^2 inside, the sides' 4(m - 1) vertices in pairs but their 4 midpoints,
    // and the corners' one: m^2 + 2, as Euler's V - E + F = 2 with m^2 cells of two triangles.
    EXPECT_EQ(canonicals.size(), std::size_t(m) * std::size_t(m) + 2);
  }
}

// The error bounds and the tessellator take positions by rows and in scattered batches
// (vectorised loops, cloned for AVX2 and AVX-512): they must be position()'s bit for bit, the
// folded sides' vertices (computed at their canonical vertex in another row) included, or twins
// would differ and the bounds with the machine. Every row whole and in pieces that start and end
// on the sides and inside; every vertex scattered, in an order that mixes rows.
TEST(OctahedralChart, RowAndScatteredPositionsAreBitwisePositions) {
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (const Mapping mapping : kOctahedralMappings) {
    const core::OctahedralChart c(core::GridSize(6), 6372790.0, mapping);
    const int m = c.grid().m();
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> height(-8000.0f, 8000.0f);
    std::vector<float> h(c.grid().count());
    for (float& x : h) x = height(rng);
    // A result the loops ASSERT on (an ASSERT here would end only the lambda).
    auto isPosition = [&](int u, int v, double x, double y, double z) -> testing::AssertionResult {
      const Eigen::Vector3d p = c.position(u, v, double(h[c.grid().index(u, v)]));
      if (bits(x) == bits(p.x()) && bits(y) == bits(p.y()) && bits(z) == bits(p.z()))
        return testing::AssertionSuccess();
      return testing::AssertionFailure() << c.name() << " vertex (" << u << ", " << v << ")";
    };
    std::vector<double> x(std::size_t(m) + 1), y(x.size()), z(x.size());
    for (int v = 0; v <= m; ++v) {
      for (const auto& [uFirst, uLast] :
           {std::pair{0, m}, std::pair{0, 0}, std::pair{m, m}, std::pair{1, m - 1},
            std::pair{3, 40}, std::pair{0, 7}, std::pair{m - 9, m}}) {
        c.rowPositions(v, uFirst, uLast, h.data() + c.grid().index(0, v),
                       {x.data(), y.data(), z.data()});
        for (int u = uFirst; u <= uLast; ++u) {
          const std::size_t k = std::size_t(u - uFirst);
          ASSERT_TRUE(isPosition(u, v, x[k], y[k], z[k]))
              << "row " << v << " [" << uFirst << ", " << uLast << "]";
        }
      }
    }
    std::vector<std::int32_t> us, vs;
    std::vector<float> hs;
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        us.push_back(u), vs.push_back(v), hs.push_back(h[c.grid().index(u, v)]);
      }
    std::shuffle(us.begin(), us.end(), std::mt19937(3));
    std::shuffle(vs.begin(), vs.end(), std::mt19937(3));  // the same permutation
    std::shuffle(hs.begin(), hs.end(), std::mt19937(3));
    const std::size_t n = us.size() - 3;  // a remainder after any vector width
    std::vector<double> sx(n), sy(n), sz(n);
    c.scatteredPositions(us.data(), vs.data(), hs.data(), n, {sx.data(), sy.data(), sz.data()});
    for (std::size_t k = 0; k < n; ++k)
      ASSERT_TRUE(isPosition(us[k], vs[k], sx[k], sy[k], sz[k])) << "scattered, entry " << k;
  }
}

// Equal area: every cell of the grid covers the same area of the sphere (to the chord
// quadrilateral's approximation); the central projection's cells differ by about 5x.
TEST(OctahedralChart, EqualAreaCellsAreEqualAndCentralOnesAreNot) {
  for (const Mapping mapping : kOctahedralMappings) {
    const core::OctahedralChart c(core::GridSize(7), 1.0, mapping);
    const int m = c.grid().m();
    double lo = INFINITY, hi = 0;
    for (int v = 0; v < m; ++v)
      for (int u = 0; u < m; ++u) {
        // The cell's area on the sphere, from 4 x 4 chord quadrilaterals (a cell that a
        // diagonal crease crosses bends along it).
        double area = 0;
        for (int j = 0; j < 4; ++j)
          for (int i = 0; i < 4; ++i) {
            const double x = u + 0.25 * i, y = v + 0.25 * j;
            const Eigen::Vector3d a = c.positionAt(x, y, 0), b = c.positionAt(x + 0.25, y, 0),
                                  d = c.positionAt(x, y + 0.25, 0),
                                  e = c.positionAt(x + 0.25, y + 0.25, 0);
            area += 0.5 * (e - a).cross(d - b).norm();
          }
        lo = std::min(lo, area);
        hi = std::max(hi, area);
      }
    if (mapping == Mapping::kEqualArea) {
      EXPECT_LT(hi / lo, 1.05) << "equal area";
    } else {
      EXPECT_GT(hi / lo, 3.0) << "central";
    }
    RecordProperty(c.name() + "_cell_area_ratio", std::to_string(hi / lo));
  }
}

// Random edits, across the folds and at the south pole's corners, then the bounds updated over
// the edit's rectangle equal a full rebuild bit for bit (the update computes the rectangle's
// mirror images where it reaches a side, and combines the twins).
TEST(OctahedralChart, LocalBoundUpdatesEqualAFullRebuildBitForBit) {
  for (const Mapping mapping : kOctahedralMappings) {
    auto t = testkit::bumpyOctahedralTerrain(7, 5, 4000.0, mapping);
    const auto g = t.grid();
    const int m = g.m();
    std::mt19937 rng(17);
    for (int trial = 0; trial < 16; ++trial) {
      int u0 = int(rng() % std::uint32_t(m + 1)), v0 = int(rng() % std::uint32_t(m + 1));
      const int w = 1 + int(rng() % 20), hgt = 1 + int(rng() % 20);
      if (trial % 4 == 0) v0 = 0;                // on the side v = 0
      if (trial % 4 == 1) u0 = m - w;            // on the side u = m
      if (trial % 4 == 2) u0 = 0, v0 = m - hgt;  // at a corner: the south pole
      u0 = std::clamp(u0, 0, m - w);
      v0 = std::clamp(v0, 0, m - hgt);
      const terrain::VertexBox region{u0, u0 + w, v0, v0 + hgt};
      auto h = t.mutableHeights();
      const float bump = float(50 + rng() % 400);
      for (int v = region.vBegin; v <= region.vEnd; ++v)
        for (int u = region.uBegin; u <= region.uEnd; ++u)
          edit::applyToVertex(t.chart(), h, u, v, h[g.index(u, v)] + bump);
      t.commitEdit(region);
      terrain::ErrorBounds full;
      full.build(t.chart(), t.heights(), terrain::ErrorRule::kHybridExact);
      ASSERT_EQ(full.errorCodes(), t.bounds().errorCodes())
          << t.chart().name() << " trial " << trial << " " << region.describe();
      ASSERT_EQ(full.radiusCodes(), t.bounds().radiusCodes()) << "trial " << trial;
      ASSERT_TRUE(full.lattice() == t.bounds().lattice()) << "trial " << trial;
    }
    // The terrain's own rule: its twins still agree (Terrain refuses heights where they do not).
    EXPECT_NO_THROW(terrain::Terrain::validateHeights(t.chart(), t.heights()));
  }
}

// The tessellator reads a vertex of half-size 8 and up from the lattice: there every vertex
// holds its codes, twins across a fold included (their combined codes). A twin's entry copied
// before the twins were combined held its own half's codes, the twins split differently, and a
// coarse view cracked along the fold (StressEdits.RandomBrushActionsOnTheOctahedralChart... at
// 8x its size, action 5489: the side u = m split at (m, 3m/4) and not at (m, m/4)).
TEST(OctahedralChart, TheLatticeHoldsEveryVertexsCodesTwinsIncluded) {
  for (const Mapping mapping : kOctahedralMappings) {
    auto t = testkit::bumpyOctahedralTerrain(7, 5, 4000.0, mapping);
    EXPECT_TRUE(edittest::latticeHoldsTheCodes(t)) << "built";
    edit::EditPipeline pipe(t);
    const double R = t.chart().sphereRadius();
    for (const Eigen::Vector3d& spot :
         {Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 0, -0.2), Eigen::Vector3d(0.3, -1, 0.1)}) {
      edit::BrushSettings b;
      b.radius = 0.4 * R;
      b.strength = 2500;
      pipe.apply(edit::GaussianBrush(b), {R * spot.normalized(), 0.0});
      EXPECT_TRUE(edittest::latticeHoldsTheCodes(t)) << "after an edit at " << spot.transpose();
    }
  }
}

// An edit whose changed vertices fill a box's octagon (terrain::CutBox: a triangle in a
// corner of the grid, as a disc about the south pole is, a diamond about the centre, as about
// the north pole, random octagons anywhere): the bounds updated over the cut regions equal a
// full rebuild bit for bit, and the triangle and the diamond cost less than their boxes.
TEST(OctahedralChart, CutBoundUpdatesEqualAFullRebuildAndSkipTheBoxsCorners) {
  auto t = testkit::bumpyOctahedralTerrain(8, 5, 4000.0);
  auto boxed = testkit::bumpyOctahedralTerrain(8, 5, 4000.0);
  const auto g = t.grid();
  const int m = g.m();
  std::mt19937 rng(23);
  for (int trial = 0; trial < 24; ++trial) {
    const int w = 4 + int(rng() % 40);
    terrain::CutBox edit;
    if (trial % 3 == 0) {  // the corner (0, 0): u + v <= w
      edit.box = {0, w, 0, w};
      edit.cut.sumMax = w;
    } else if (trial % 3 == 1) {  // a diamond about the centre: |u - m/2| + |v - m/2| <= w
      edit.box = {m / 2 - w, m / 2 + w, m / 2 - w, m / 2 + w};
      edit.cut = {m - w, m + w, -w, w};
    } else {  // any octagon, sides and corners included
      const int uc = int(rng() % std::uint32_t(m + 1)), vc = int(rng() % std::uint32_t(m + 1));
      edit.box = {std::max(0, uc - w), std::min(m, uc + w), std::max(0, vc - w),
                  std::min(m, vc + w)};
      const int a = int(rng() % std::uint32_t(2 * w + 1)),
                b = int(rng() % std::uint32_t(2 * w + 1));
      edit.cut = {uc + vc - a, uc + vc + int(rng() % 8), uc - vc - b, uc - vc + int(rng() % 8)};
    }
    // The changed vertices: the octagon, and their twins across the folds.
    auto h = t.mutableHeights();
    auto hb = boxed.mutableHeights();
    // Random per vertex: a bump by one value would leave many diamonds' shapes as they were.
    std::uniform_real_distribution<float> bump(-3000.0f, 3000.0f);
    int changed = 0;
    for (int v = edit.box.vBegin; v <= edit.box.vEnd; ++v)
      for (int u = std::max(edit.box.uBegin, edit.cut.firstColumn(v));
           u <= std::min(edit.box.uEnd, edit.cut.lastColumn(v)); ++u) {
        const float x = bump(rng);
        edit::applyToVertex(t.chart(), h, u, v, h[g.index(u, v)] + x);
        edit::applyToVertex(boxed.chart(), hb, u, v, hb[g.index(u, v)] + x);
        ++changed;
      }
    if (changed == 0) continue;
    const std::vector<terrain::CutBox> images = terrain::gluedImages(t.chart(), edit, false);
    t.commitEdit(images);
    boxed.commitEdit(edit.box);
    terrain::ErrorBounds full;
    full.build(t.chart(), t.heights(), terrain::ErrorRule::kHybridExact);
    ASSERT_EQ(full.errorCodes(), t.bounds().errorCodes()) << "trial " << trial;
    ASSERT_EQ(full.radiusCodes(), t.bounds().radiusCodes()) << "trial " << trial;
    ASSERT_TRUE(full.lattice() == t.bounds().lattice()) << "trial " << trial;
    if (trial % 3 != 2 && w >= 16) {  // (the levels' growth fills small octagons' boxes)
      EXPECT_LT(double(t.bounds().lastUpdateVertexCount()),
                0.8 * double(boxed.bounds().lastUpdateVertexCount()))
          << "trial " << trial << " w " << w;
    }
  }
}

// Views over the north pole, the south pole (a corner of the grid), a side's fold and a crease:
// the tessellation is crack-free across every fold and its measured screen error is never above
// dist_max.
TEST(OctahedralChart, TessellationsAreCrackFreeAndWithinDistMax) {
  for (const Mapping mapping : kOctahedralMappings) {
    const auto t = testkit::bumpyOctahedralTerrain(8, 7, 6000.0, mapping);
    const double R = t.chart().sphereRadius();
    const std::array<Eigen::Vector3d, 5> looks{
        Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.05, 0.02, -1),
        Eigen::Vector3d(0.7, 0.01, -0.7),  // the fold of side u = m, south of the equator
        Eigen::Vector3d(0.5, 0.5, 0.05),   // a crease at the equator
        Eigen::Vector3d(-0.3, 0.8, -0.5)};
    for (const auto& dir : looks) {
      const Eigen::Vector3d d = dir.normalized();
      for (double altitude : {3e6, 3e5}) {
        const auto cam = terrain::Camera::lookAt((R + altitude) * d, R * d, d.unitOrthogonal(), 320,
                                                 240, 60 * M_PI / 180);
        terrain::Tessellator tess;
        terrain::TessellationSettings ts;
        ts.distMaxPx = 2;
        ts.triangleBudget = 0;
        const auto& mesh = tess.tessellate(t, cam, ts);
        ASSERT_GT(mesh.triangleCount(), 20u);
        EXPECT_LE(terrain::measureScreenError(t, cam, mesh).maxPx, ts.distMaxPx + 1e-6)
            << t.chart().name() << " " << d.transpose() << " at " << altitude;
        // The whole planet (culling off) for the same view: no crack anywhere.
        ts.cull = false;
        terrain::Tessellator whole;
        EXPECT_EQ(testkit::conformityDefect(t, whole.tessellate(t, cam, ts)), "")
            << t.chart().name() << " " << d.transpose();
      }
    }
  }
}

// A whole planet meshed to an error and welded by the chart: a closed 2-manifold, Euler 2, every
// full-resolution vertex within the error.
TEST(OctahedralChart, WholePlanetMeshesAreWeldedSpheres) {
  for (const Mapping mapping : kOctahedralMappings) {
    const auto t = testkit::bumpyOctahedralTerrain(7, 2, 5000.0, mapping);
    for (double error : {20000.0, 2000.0}) {
      const terrain::Mesh mesh = terrain::meshToError(t, error);
      EXPECT_LE(terrain::measureTrueError(t, mesh), error);
      const terrain::Mesh welded = io::weldMesh(t, mesh);
      std::vector<std::array<std::uint32_t, 3>> triangles;
      for (std::size_t k = 0; k + 2 < welded.indices.size(); k += 3)
        triangles.push_back({welded.indices[k], welded.indices[k + 1], welded.indices[k + 2]});
      const tin::MeshTopology top = tin::meshTopology(welded.gridIndex.size(), triangles);
      EXPECT_EQ(top.borderEdges, 0u) << t.chart().name() << " at " << error;
      EXPECT_EQ(top.nonManifoldEdges, 0u);
      EXPECT_EQ(top.degenerate, 0u);
      EXPECT_EQ(top.euler(), 2) << t.chart().name() << " at " << error;
    }
  }
}

// Region growing and the brush take a row's distances at once (DistanceField::rowDistances2,
// by the chart's row positions): they must be distance2()'s bit for bit, or the region would
// differ from brute force at its rim. Whole rows and pieces, the sides and corners included.
TEST(OctahedralChart, RowDistancesAreBitwiseDistances) {
  for (const Mapping mapping : kOctahedralMappings) {
    const auto chart = std::make_shared<core::OctahedralChart>(core::GridSize(6), 6.4e6, mapping);
    const int m = chart->grid().m();
    edit::DistanceField field(chart);
    std::vector<double> d(std::size_t(m) + 1);
    for (const core::GridPoint c : {core::GridPoint{m / 2, m / 2}, core::GridPoint{0, 0},
                                    core::GridPoint{m, 17}, core::GridPoint{23, 41}}) {
      field.setCentre(c);
      for (int v = 0; v <= m; ++v)
        for (const auto& [uFirst, uLast] :
             {std::pair{0, m}, std::pair{0, 0}, std::pair{m, m}, std::pair{5, 50}}) {
          field.rowDistances2(v, uFirst, uLast, d.data());
          for (int u = uFirst; u <= uLast; ++u)
            ASSERT_EQ(std::bit_cast<std::uint64_t>(d[std::size_t(u - uFirst)]),
                      std::bit_cast<std::uint64_t>(field.distance2(u, v)))
                << chart->name() << " (" << u << ", " << v << ") centre " << c.u << "," << c.v;
        }
    }
  }
}

// Region growing across the folds equals brute force (every vertex within the radius in 3D):
// centres at the north pole, the south pole (the corners), on a side's fold, at a side's
// midpoint (an octahedron vertex on the equator), near the midlines, anywhere; radii from a
// cell to a quarter of the planet.
TEST(OctahedralChart, RegionGrowingAcrossTheFoldsEqualsBruteForce) {
  const auto chart = testkit::octahedralChart(7);
  const int m = chart->grid().m();
  edit::DistanceField field(chart);
  edit::RegionGrower grower;
  edit::Region region;
  std::mt19937 rng(23);
  std::vector<core::GridPoint> centres{
      {m / 2, m / 2}, {0, 0},     {m, m},          {0, 40},     {m, 90},           {70, 0},
      {m / 2, 0},     {m, m / 2}, {m / 2 - 1, 30}, {20, m / 2}, {m / 2 + 3, m - 5}};
  for (int k = 0; k < 12; ++k)
    centres.push_back({int(rng() % std::uint32_t(m + 1)), int(rng() % std::uint32_t(m + 1))});
  const double R = chart->sphereRadius();
  std::vector<std::uint8_t> mask;
  for (const core::GridPoint& c : centres) {
    for (double radius : {0.01 * R, 0.1 * R, 0.4 * R, 1.2 * R}) {
      field.setCentre(c);
      grower.grow(field, radius, region);
      const std::size_t brute = edit::bruteForceRegion(field, radius, &mask);
      ASSERT_EQ(region.vertexCount(), brute) << "centre " << c.u << "," << c.v << " r " << radius;
      for (int v = 0; v <= m; ++v)
        for (int u = 0; u <= m; ++u)
          ASSERT_EQ(region.contains(u, v), mask[chart->grid().index(u, v)] != 0)
              << "(" << u << "," << v << ") centre " << c.u << "," << c.v << " r " << radius;
      // Every vertex lies in an image of the dirty box.
      const auto images = terrain::gluedImages(*chart, region.bounds());
      testing::AssertionResult allInImages = testing::AssertionSuccess();  // the first outside
      region.forEachSpan([&](int v, int a, int b) {
        for (int u = a; u <= b && allInImages; ++u) {
          const bool inImage = std::any_of(images.begin(), images.end(), [&](const auto& r) {
            return u >= r.uBegin && u <= r.uEnd && v >= r.vBegin && v <= r.vEnd;
          });
          if (!inImage)
            allInImages = testing::AssertionFailure() << "(" << u << "," << v << ") in no image";
        }
      });
      ASSERT_TRUE(allInImages) << "centre " << c.u << "," << c.v << " r " << radius << " box "
                               << region.bounds().describe();
    }
  }
}

// Brush strokes anywhere, across the folds and over the south pole, through the edit pipeline:
// the bounds equal a full rebuild bit for bit after each, twins stay one height, every vertex
// that changed lies in an image of the reported dirty box, and undo gives the heights back.
TEST(OctahedralChart, BrushEditsKeepBoundsTwinsAndUndo) {
  auto t = testkit::bumpyOctahedralTerrain(7, 9, 3000.0);
  const double R = t.chart().sphereRadius();
  const auto g = t.grid();
  const std::vector<float> original(t.heights().begin(), t.heights().end());
  edit::EditPipeline pipe(t);
  std::mt19937 rng(31);
  std::normal_distribution<double> n01;
  std::vector<Eigen::Vector3d> spots{Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(0, 0, 1),
                                     Eigen::Vector3d(-1, 0.001, -0.3), Eigen::Vector3d(1, 0, 0)};
  for (int k = 0; k < 8; ++k) spots.emplace_back(n01(rng), n01(rng), n01(rng));
  int edits = 0;
  for (const auto& spot : spots) {
    const std::vector<float> before(t.heights().begin(), t.heights().end());
    edit::BrushSettings b;
    b.radius = (0.05 + 0.3 * std::abs(n01(rng))) * R;
    b.strength = 1500;
    const auto rep = pipe.apply(edit::GaussianBrush(b), {R * spot.normalized(), 0.0});
    ++edits;
    ASSERT_GT(rep.modifiedVertices, 0u);
    terrain::ErrorBounds full;
    full.build(t.chart(), t.heights(), terrain::ErrorRule::kHybridExact);
    ASSERT_EQ(full.errorCodes(), t.bounds().errorCodes()) << spot.transpose();
    ASSERT_EQ(full.radiusCodes(), t.bounds().radiusCodes()) << spot.transpose();
    ASSERT_NO_THROW(terrain::Terrain::validateHeights(t.chart(), t.heights()));
    const auto images = terrain::gluedImages(t.chart(), rep.dirty);
    for (int v = 0; v <= g.m(); ++v)
      for (int u = 0; u <= g.m(); ++u) {
        if (before[g.index(u, v)] == t.heights()[g.index(u, v)]) continue;
        ASSERT_TRUE(std::any_of(images.begin(), images.end(),
                                [&](const auto& r) {
                                  return u >= r.uBegin && u <= r.uEnd && v >= r.vBegin &&
                                         v <= r.vEnd;
                                }))
            << "(" << u << "," << v << ") changed outside the dirty box's images";
      }
  }
  for (int k = 0; k < edits; ++k) pipe.undo();
  EXPECT_TRUE(std::equal(original.begin(), original.end(), t.heights().begin()));
  terrain::ErrorBounds full;
  full.build(t.chart(), t.heights(), terrain::ErrorRule::kHybridExact);
  EXPECT_EQ(full.errorCodes(), t.bounds().errorCodes());
}
