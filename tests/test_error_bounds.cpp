#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <random>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "terrain/diamond.hpp"
#include "terrain/terrain.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using terrain::Diamond;
using terrain::ErrorRule;
using terrain::GridPoint;
using terrain::VertexBox;

namespace {

// Brute force over every vertex of the grid: the exact deviation of the full-resolution
// vertices inside v's diamond from the diamond's two triangles, and their largest distance from v.
struct Exact {
  double deviation = 0, reach = 0;
};

Exact exactDiamond(const terrain::Terrain& t, GridPoint p) {
  const auto& chart = t.chart();
  const auto g = t.grid();
  const int m = g.m();
  auto pos = [&](GridPoint q) { return chart.position(q.u, q.v, double(t.height(q.u, q.v))); };
  Exact e;
  const Eigen::Vector3d P = pos(p);
  // Both halves; a half beyond the seam is taken from the twin's side.
  auto half = [&](GridPoint a, GridPoint b0, GridPoint b1) {
    if (a.v < 0 || a.v > m) return;
    int shift = 0;
    if ((a.u < 0 || a.u > m) && !chart.wrapsU()) return;  // a flat chart's edge: no such half
    if (a.u < 0) shift = m;
    if (a.u > m) shift = -m;
    a.u += shift, b0.u += shift, b1.u += shift;
    if (b0.u < 0 || b0.u > m || b1.u < 0 || b1.u > m) return;
    const Eigen::Vector3d pa = pos(a), d0 = pos(b0) - pa, d1 = pos(b1) - pa;
    for (int v = 0; v <= m; ++v) {
      for (int u = 0; u <= m; ++u) {
        const long long da =
            (long long)(u - a.u) * (b0.u - a.u) + (long long)(v - a.v) * (b0.v - a.v);
        const long long db =
            (long long)(u - a.u) * (b1.u - a.u) + (long long)(v - a.v) * (b1.v - a.v);
        const long long l2 =
            (long long)(b0.u - a.u) * (b0.u - a.u) + (long long)(b0.v - a.v) * (b0.v - a.v);
        if (da < 0 || db < 0 || da + db > l2) continue;
        const Eigen::Vector3d q = pos({u, v});
        const Eigen::Vector3d lin =
            pa + double(da) / double(l2) * d0 + double(db) / double(l2) * d1;
        e.deviation = std::max(e.deviation, (q - lin).norm());
        e.reach = std::max(e.reach, (q - P).norm());
      }
    }
  };
  const Diamond d = Diamond::of(p);
  half(d.apex0, d.base0, d.base1);
  half(d.apex1, d.base1, d.base0);
  return e;
}

bool isCorner(const core::GridSize& g, GridPoint p) {
  return (p.u == 0 || p.u == g.m()) && (p.v == 0 || p.v == g.m());
}

class BoundsRule : public ::testing::TestWithParam<ErrorRule> {};

}  // namespace

TEST(Diamond, LevelsAndChildrenFollowTheHierarchy) {
  const core::GridSize g(5);
  const Diamond root = Diamond::of({16, 16});
  EXPECT_TRUE(root.isCentre);
  EXPECT_EQ(root.level, 2 * g.n() - 1);
  EXPECT_EQ(root.base0, (GridPoint{0, 0}));
  EXPECT_EQ(root.base1, (GridPoint{32, 32}));
  // Every non-corner vertex is a child of each of its in-grid parents.
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      if (isCorner(g, {u, v}) || (u == 16 && v == 16)) continue;
      const Diamond d = Diamond::of({u, v});
      int parents = 0;
      for (GridPoint a : {d.apex0, d.apex1}) {
        if (!terrain::inGrid(g, a)) continue;
        ++parents;
        const Diamond pd = Diamond::of(a);
        EXPECT_EQ(pd.level, d.level + 1);
        const bool found = std::find(pd.children.begin(), pd.children.begin() + pd.childCount,
                                     GridPoint{u, v}) != pd.children.begin() + pd.childCount;
        EXPECT_TRUE(found) << u << "," << v;
      }
      EXPECT_GE(parents, 1);
    }
  }
}

TEST_P(BoundsRule, ErrorAndRadiusAreGuaranteedAndNested) {
  for (int seed : {1, 2}) {
    const auto t = testkit::bumpyTerrain(6, seed, 9000.0, GetParam());
    const auto g = t.grid();
    const int m = g.m();
    const auto& b = t.bounds();
    double worstRatio = 0;
    for (int v = 0; v <= m; ++v) {
      for (int u = 0; u <= m; ++u) {
        if (isCorner(g, {u, v})) continue;
        const std::size_t i = g.index(u, v);
        const Exact e = exactDiamond(t, {u, v});
        ASSERT_GE(double(b.error(i)), e.deviation) << "error bound broken at " << u << "," << v;
        ASSERT_GE(double(b.radius(i)), e.reach) << "radius bound broken at " << u << "," << v;
        if (e.deviation > 0) worstRatio = std::max(worstRatio, e.deviation / b.error(i));
        // Nesting with every in-grid parent (across the seam through the twin).
        const Diamond d = Diamond::of({u, v});
        const Eigen::Vector3d P = t.chart().position(u, v, t.height(u, v));
        for (GridPoint a : {d.apex0, d.apex1}) {
          if (a.v < 0 || a.v > m) continue;
          if (a.u < 0) a.u += m;
          if (a.u > m) a.u -= m;
          if (isCorner(g, a)) continue;
          const std::size_t pi = g.index(a.u, a.v);
          ASSERT_LE(b.error(i), b.error(pi)) << "error nesting at " << u << "," << v;
          const Eigen::Vector3d Pp = t.chart().position(a.u, a.v, t.height(a.u, a.v));
          ASSERT_LE(double(b.radius(i)) + (P - Pp).norm(), double(b.radius(pi)))
              << "radius nesting at " << u << "," << v;
        }
      }
    }
    for (int v = 0; v <= m; ++v) {
      ASSERT_EQ(b.errorCodes()[g.index(0, v)], b.errorCodes()[g.index(m, v)])
          << "seam twins v=" << v;
      ASSERT_EQ(b.radiusCodes()[g.index(0, v)], b.radiusCodes()[g.index(m, v)])
          << "seam twins v=" << v;
    }
    EXPECT_GT(worstRatio, 0.3) << "the bound is not uselessly loose everywhere";
  }
}

TEST_P(BoundsRule, LocalUpdateEqualsFullRebuildBitForBit) {
  auto t = testkit::bumpyTerrain(7, 5, 4000.0, GetParam());
  const auto g = t.grid();
  const int m = g.m();
  std::mt19937 rng(11);
  for (int trial = 0; trial < 12; ++trial) {
    // A random rectangle, sometimes across the seam or touching a pole.
    int u0 = int(rng() % (m + 1)), v0 = int(rng() % (m + 1));
    const int w = 1 + int(rng() % 20), hgt = 1 + int(rng() % 20);
    if (trial % 4 == 0) u0 = m - w / 2;  // straddles the seam
    if (trial % 4 == 1) v0 = 0;          // touches the south pole
    const int v1 = std::min(m, v0 + hgt);
    auto h = t.mutableHeights();
    VertexBox region{u0, u0 + w, v0, v1};
    for (int v = v0; v <= v1; ++v) {
      const bool pole = (v == 0 || v == m);
      for (int du = 0; du <= (pole ? m : w); ++du) {
        const int u = pole ? du : (u0 + du) % m;
        h[g.index(u, v)] += 100.0f;
        if (u == 0) h[g.index(m, v)] = h[g.index(0, v)];
      }
      if (pole) region = region.unite(VertexBox{0, m, v, v}, g, true);
    }
    // Re-sync: an update that wrapped may have touched column 0 without m or vice versa.
    for (int v = v0; v <= v1; ++v) h[g.index(m, v)] = h[g.index(0, v)];
    if (v0 == 0) {
      for (int u = 0; u <= m; ++u) h[g.index(u, 0)] = h[g.index(0, 0)];
    }
    t.commitEdit(region.unite(VertexBox{0, 0, v0, v1}, g, true));
    terrain::ErrorBounds full;
    full.build(t.chart(), t.heights(), GetParam());
    ASSERT_EQ(full.errorCodes(), t.bounds().errorCodes())
        << "trial " << trial << " " << region.describe();
    ASSERT_EQ(full.radiusCodes(), t.bounds().radiusCodes()) << "trial " << trial;
    ASSERT_TRUE(full.lattice() == t.bounds().lattice()) << "trial " << trial;
    // The packed lattice the tessellator reads holds what the full arrays hold, each vertex at
    // its own entry, and a level's view addresses the same entries; the children's largest
    // error is that of the midpoints of the diamond's four legs (apex to base) in the grid.
    const auto& bounds = t.bounds();
    std::vector<int> owner(bounds.lattice().size(), 0);
    constexpr int kStep = 1 << terrain::ErrorBounds::kLatticeShift;
    for (int v = 0; v <= m; v += kStep) {
      for (int u = 0; u <= m; u += kStep) {
        if ((u == 0 || u == m) && (v == 0 || v == m)) continue;  // corners split nothing
        const std::size_t i = g.index(u, v);
        const std::size_t at = bounds.latticeIndex(u, v);
        ASSERT_LT(at, owner.size()) << "lattice vertex (" << u << ", " << v << ")";
        ASSERT_EQ(owner[at]++, 0) << "two lattice vertices share entry " << at;
        const int b = std::countr_zero(unsigned(u | v));
        const auto level = bounds.latticeLevel(1 << b, ((u >> b) & (v >> b) & 1) != 0);
        ASSERT_EQ(&level.at(u, v), &bounds.lattice()[at]) << "(" << u << ", " << v << ")";
        const terrain::Diamond d = terrain::Diamond::of({u, v});
        std::uint16_t childError = 0;
        for (const auto apex : {d.apex0, d.apex1}) {
          for (const auto base : {d.base0, d.base1}) {
            const core::GridPoint mid{(apex.u + base.u) / 2, (apex.v + base.v) / 2};
            if (mid.u >= 0 && mid.u <= m && mid.v >= 0 && mid.v <= m)
              childError = std::max(childError, bounds.codes()[g.index(mid.u, mid.v)].error);
          }
        }
        const terrain::LatticeEntry expected{t.heights()[i], bounds.codes()[i], childError};
        ASSERT_TRUE(bounds.lattice()[at] == expected)
            << "trial " << trial << " lattice vertex (" << u << ", " << v << ")";
      }
    }
  }
}

// The bounds of levels 0-5 come from row kernels that work in runs of up to 64 vertices and in
// bands of 8 rows sharing rows of positions; a 513² grid has rows of 256 leaves, so wide edits
// cross run boundaries, and rows of either parity start their runs one column apart. Wide and
// narrow edits at random offsets (across the seam, at a pole, at a flat chart's edges), then the
// bounds equal a full rebuild, bit for bit.
TEST_P(BoundsRule, WideLocalUpdatesEqualAFullRebuildAcrossKernelRuns) {
  std::vector<terrain::Terrain> planets;
  planets.push_back(testkit::bumpyTerrain(9, 8, 6000.0, GetParam()));
  auto flat = std::make_shared<core::FlatChart>(core::GridSize(9), 30.0, 20.0);
  std::mt19937 heightsRng(4);
  std::uniform_real_distribution<float> noise(-200.0f, 200.0f);
  std::vector<float> fh(flat->grid().count());
  for (auto& x : fh) x = noise(heightsRng);
  planets.push_back(terrain::Terrain(flat, fh, GetParam()));
  for (auto& t : planets) {
    const auto g = t.grid();
    const int m = g.m();
    const bool sphere = t.chart().wrapsU();
    std::mt19937 rng(23);
    for (int trial = 0; trial < 6; ++trial) {
      const int w = trial % 2 == 0 ? 150 + int(rng() % 300) : 1 + int(rng() % 9);
      const int hgt = 1 + int(rng() % 40);
      int u0 = int(rng() % std::uint32_t(m - w)), v0 = int(rng() % std::uint32_t(m - hgt));
      if (trial == 2) u0 = sphere ? m - w / 2 : 0;  // across the seam / at the flat chart's edge
      if (trial == 3) v0 = m - hgt;                 // a pole row / the flat chart's top edge
      const int v1 = v0 + hgt;
      auto h = t.mutableHeights();
      VertexBox region{u0, u0 + w, v0, v1};
      for (int v = v0; v <= v1; ++v) {
        const bool pole = sphere && (v == 0 || v == m);
        for (int du = 0; du <= (pole ? m : w); ++du) {
          const int u = pole ? du : (sphere ? (u0 + du) % m : std::min(m, u0 + du));
          h[g.index(u, v)] += 50.0f + float(du % 7);
        }
        if (pole) {
          for (int u = 0; u <= m; ++u) h[g.index(u, v)] = h[g.index(0, v)];
          region = region.unite(VertexBox{0, m, v, v}, g, sphere);
        }
        if (sphere) h[g.index(m, v)] = h[g.index(0, v)];
      }
      if (sphere) region = region.unite(VertexBox{0, 0, v0, v1}, g, true);
      t.commitEdit(region);
      ASSERT_TRUE(edittest::boundsEqualFullRebuild(t))
          << t.chart().name() << " trial " << trial << " " << region.describe();
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Rules, BoundsRule,
                         ::testing::Values(ErrorRule::kWedgie, ErrorRule::kHybridExact),
                         [](const auto& p) {
                           return p.param == ErrorRule::kWedgie ? "Wedgie" : "HybridExact";
                         });

// The flat chart takes its own path (the deviation is the height's alone): still a bound, on
// rough terrain where the exact levels matter.
TEST(ErrorBounds, FlatChartErrorIsGuaranteedAndNested) {
  auto chart = std::make_shared<core::FlatChart>(core::GridSize(6), 25.0, 25.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(-300.0f, 300.0f);
  std::vector<float> h(chart->grid().count());
  for (auto& x : h) x = noise(rng);
  const terrain::Terrain t(chart, h);
  const auto g = t.grid();
  double worstRatio = 0;
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      if (isCorner(g, {u, v})) continue;
      const Exact e = exactDiamond(t, {u, v});
      const float bound = t.bounds().error(g.index(u, v));
      ASSERT_GE(double(bound), e.deviation) << "flat error bound broken at " << u << "," << v;
      ASSERT_GE(double(t.bounds().radius(g.index(u, v))), e.reach) << u << "," << v;
      if (e.deviation > 0) worstRatio = std::max(worstRatio, e.deviation / bound);
    }
  }
  EXPECT_GT(worstRatio, 0.99) << "the exact levels should be tight on a flat chart";
}

// An export-only build skips the radii: the errors must be the ones a full build gives, bit for
// bit (through local updates too), and a view-dependent tessellation must refuse the terrain
// instead of projecting every triangle as a point.
TEST(ErrorBounds, ErrorsOnlyBuildHasTheFullBuildsErrors) {
  auto flat = std::make_shared<core::FlatChart>(core::GridSize(6), 10.0, 10.0);
  std::vector<float> fh(flat->grid().count());
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> noise(-50.0f, 50.0f);
  for (auto& x : fh) x = noise(rng);
  std::vector<terrain::Terrain> pairs;
  pairs.push_back(testkit::bumpyTerrain(6, 3, 9000.0, ErrorRule::kHybridExact));
  pairs.push_back(terrain::Terrain(flat, fh));
  for (auto& full : pairs) {
    terrain::Terrain lean(full.chartPtr(),
                          std::vector<float>(full.heights().begin(), full.heights().end()),
                          ErrorRule::kHybridExact, terrain::BoundsContent::kErrorsOnly);
    EXPECT_FALSE(lean.bounds().hasRadii());
    EXPECT_TRUE(full.bounds().hasRadii());
    ASSERT_EQ(lean.bounds().errorCodes(), full.bounds().errorCodes());
    const auto radii = lean.bounds().radiusCodes();
    EXPECT_TRUE(std::all_of(radii.begin(), radii.end(), [](auto c) { return c == 0; }));
    // The same local edit on both: errors still equal, the lean one still without radii.
    const auto g = full.grid();
    for (auto* t : {&full, &lean}) {
      auto h = t->mutableHeights();
      for (int v = 10; v <= 14; ++v)
        for (int u = 20; u <= 23; ++u) h[g.index(u, v)] += 7.0f;
      t->commitEdit(VertexBox{20, 23, 10, 14});
    }
    ASSERT_EQ(lean.bounds().errorCodes(), full.bounds().errorCodes());
    EXPECT_FALSE(lean.bounds().hasRadii());
    const auto cam = terrain::Camera::lookAt({0, 0, 3 * testkit::kEarthRadius}, {0, 0, 0},
                                             {1, 0, 0}, 640, 480, 1.0);
    terrain::Tessellator tess;
    EXPECT_THROW(tess.tessellate(lean, cam, {}), std::logic_error);
  }
}

TEST(Terrain, RejectsBadHeightsNamingTheVertex) {
  auto chart = testkit::earthChart(5);
  std::vector<float> h(chart->grid().count(), 0.0f);
  h[chart->grid().index(3, 4)] = NAN;
  try {
    terrain::Terrain t(chart, h);
    FAIL() << "NaN accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("u=3, v=4"), std::string::npos) << e.what();
  }
  h[chart->grid().index(3, 4)] = INFINITY;
  EXPECT_THROW(terrain::Terrain(chart, h), core::InputError);
  h[chart->grid().index(3, 4)] = 0;
  h[chart->grid().index(0, 7)] = 5;  // twin at u = m still 0
  EXPECT_THROW(terrain::Terrain(chart, h), core::InputError);
  h[chart->grid().index(32, 7)] = 5;
  EXPECT_NO_THROW(terrain::Terrain(chart, h));
  h[chart->grid().index(5, 0)] = 1;  // the south pole row is not one point
  EXPECT_THROW(terrain::Terrain(chart, h), core::InputError);
  std::vector<float> wrongSize(10, 0.0f);
  EXPECT_THROW(terrain::Terrain(chart, wrongSize), core::InputError);
}
