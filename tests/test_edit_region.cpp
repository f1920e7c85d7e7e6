#include <gtest/gtest.h>

#include <random>

#include "core/input_error.hpp"
#include "edit/control_vertex.hpp"
#include "edit/distance_field.hpp"
#include "edit/region_growing.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using edit::DistanceField;
using edit::Region;
using edit::RegionGrower;

TEST(EditRegion, EqualsBruteForceAnywhere) {
  for (int n : {6, 7, 8}) {
    auto chart = testkit::earthChart(n);
    DistanceField field(chart);
    RegionGrower grower;
    Region region;
    const int m = chart->grid().m();
    std::mt19937 rng(1000 + n);
    for (int trial = 0; trial < 70; ++trial) {
      const core::GridPoint c = edittest::randomCentre(rng, m);
      const double r = edittest::randomRadius(rng, testkit::kEarthRadius, m);
      field.setCentre(c);
      grower.grow(field, r, region);
      ASSERT_TRUE(edittest::equalsBruteForce(field, r, region))
          << "n=" << n << " centre (" << c.u << "," << c.v << ") r=" << r;
      ASSERT_TRUE(region.contains(c.u, c.v));
    }
  }
}

TEST(EditRegion, PaperCellsEqualBruteForceAt2049) {
  // Paper 003's Table 1 layout: control vertex on the u = 0 meridian, pole and equator.
  auto chart = testkit::earthChart(11);
  DistanceField field(chart);
  RegionGrower grower;
  Region region;
  const int m = chart->grid().m();
  for (int v : {0, m / 2, m}) {
    for (double rKm : {150.0, 600.0}) {
      field.setCentre({0, v});
      grower.grow(field, rKm * 1000, region);
      EXPECT_EQ(region.vertexCount(), edit::bruteForceRegion(field, rKm * 1000)) << v << " " << rKm;
      if (v == 0 && rKm == 150.0) {
        // Rows 0..15 lie within 150 km of the pole (row 16 is 153 km away): 16 whole rows.
        EXPECT_EQ(region.vertexCount(), 16u * 2049u);
        EXPECT_EQ(region.pointCount(), 1u + 15u * 2048u);
      }
    }
  }
}

TEST(EditRegion, GenericChartFillEqualsBruteForce) {
  // The vertex-by-vertex fill (any chart) on a seamed chart with poles.
  auto ll = testkit::earthChart(6);
  auto chart = std::make_shared<edittest::OpaqueChart>(ll);
  DistanceField field(chart);
  ASSERT_EQ(field.latLong(), nullptr);
  RegionGrower grower;
  Region region;
  const int m = chart->grid().m();
  std::mt19937 rng(77);
  for (int trial = 0; trial < 60; ++trial) {
    const core::GridPoint c = edittest::randomCentre(rng, m);
    const double r = edittest::randomRadius(rng, testkit::kEarthRadius, m);
    field.setCentre(c);
    grower.grow(field, r, region);
    ASSERT_TRUE(edittest::equalsBruteForce(field, r, region))
        << "centre (" << c.u << "," << c.v << ") r=" << r;
    ASSERT_FALSE(region.symmetric());
  }
}

TEST(EditRegion, PredicateIsTheEuclideanDistanceBetweenSpherePositions) {
  auto chart = testkit::earthChart(7);
  DistanceField field(chart);
  const int m = chart->grid().m();
  const double R = testkit::kEarthRadius;
  std::mt19937 rng(5);
  int classified = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const core::GridPoint c = edittest::randomCentre(rng, m);
    field.setCentre(c);
    const Eigen::Vector3d pc = chart->position(c.u, c.v, 0.0);
    const double r = edittest::randomRadius(rng, R, m);
    for (int k = 0; k < 400; ++k) {
      const int u = int(rng() % unsigned(m + 1)), v = int(rng() % unsigned(m + 1));
      const double naive = (chart->position(u, v, 0.0) - pc).squaredNorm();
      ASSERT_NEAR(field.distance2(u, v), naive, 1e-12 * 4 * R * R) << u << "," << v;
      // Away from the border the naive test classifies the same way.
      if (std::abs(std::sqrt(naive) - r) > 1e-6 * r) {
        ASSERT_EQ(field.distance2(u, v) <= r * r, naive <= r * r);
        ++classified;
      }
    }
  }
  EXPECT_GT(classified, 10000);
}

TEST(EditRegion, TwinsPoleRowsCountsAndBoundsAreConsistent) {
  auto chart = testkit::earthChart(7);
  const auto g = chart->grid();
  const int m = g.m();
  DistanceField field(chart);
  RegionGrower grower;
  Region region;
  std::mt19937 rng(9);
  for (int trial = 0; trial < 60; ++trial) {
    const core::GridPoint c = edittest::randomCentre(rng, m);
    const double r = edittest::randomRadius(rng, testkit::kEarthRadius, m);
    field.setCentre(c);
    grower.grow(field, r, region);
    ASSERT_TRUE(region.symmetric());
    std::size_t points = 0;
    std::vector<std::uint8_t> inBounds(g.count(), 0);
    region.bounds().forEachColumnRange(g, [&](int a, int b) {
      for (int v = region.bounds().vBegin; v <= region.bounds().vEnd; ++v) {
        for (int u = a; u <= b; ++u) inBounds[g.index(u, v)] = 1;
      }
    });
    for (int v = 0; v <= m; ++v) {
      ASSERT_EQ(region.contains(0, v), region.contains(m, v)) << "twins, row " << v;
      int inRow = 0;
      for (int u = 0; u <= m; ++u) {
        if (!region.contains(u, v)) continue;
        ++inRow;
        ASSERT_TRUE(inBounds[g.index(u, v)])
            << "bounds miss (" << u << "," << v << ") " << region.bounds().describe();
        // Symmetric: membership is the folded column distance against the row's half-width.
        ASSERT_LE(field.fold(u), region.halfWidth(v));
      }
      if (v == 0 || v == m) {
        ASSERT_TRUE(inRow == 0 || inRow == m + 1) << "pole row " << v << " partly inside";
        points += inRow ? 1 : 0;
      } else {
        points += std::size_t(inRow) - (region.contains(m, v) ? 1 : 0);
      }
      ASSERT_LE(region.row(v).size(), 2u);
    }
    ASSERT_EQ(points, region.pointCount());
    // The bounds rectangle is tight in v.
    ASSERT_FALSE(region.row(region.bounds().vBegin).empty());
    ASSERT_FALSE(region.row(region.bounds().vEnd).empty());
  }
}

TEST(EditRegion, LatLongFillCostsRowsNotVertices) {
  auto chart = testkit::earthChart(12);  // 4097^2
  DistanceField field(chart);
  RegionGrower grower;
  Region region;
  field.setCentre({0, 0});
  grower.grow(field, 600e3, region);  // a polar cap of about half a million grid entries
  EXPECT_GT(region.vertexCount(), 400000u);
  const std::size_t rows = std::size_t(region.vEnd() - region.vBegin() + 1);
  EXPECT_LE(grower.lastEvaluations(), rows * 16);
  EXPECT_LE(region.spanCount(), 2 * rows);
}

TEST(EditRegion, RejectsBadRadiusNamingIt) {
  auto chart = testkit::earthChart(5);
  DistanceField field(chart);
  RegionGrower grower;
  Region region;
  for (double r : {0.0, -5.0, double(NAN), double(INFINITY)}) {
    try {
      grower.grow(field, r, region);
      FAIL() << "radius " << r << " accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(field.setCentre({-1, 3}), core::InputError);
  EXPECT_THROW(field.setCentre({3, 33}), core::InputError);
}

TEST(EditControlVertex, NearestMatchesAScanOfEveryVertex) {
  for (int n : {6, 7}) {
    auto ll = testkit::earthChart(n);
    auto opaque = std::make_shared<edittest::OpaqueChart>(ll);
    const int m = ll->grid().m();
    const double R = testkit::kEarthRadius;
    std::mt19937 rng(40 + n);
    std::uniform_real_distribution<double> uni(-1, 1), alt(0.3, 3.0);
    for (int trial = 0; trial < 150; ++trial) {
      Eigen::Vector3d d(uni(rng), uni(rng), uni(rng));
      if (trial % 5 == 1)
        d = Eigen::Vector3d(0.02 * uni(rng), 0.02 * uni(rng), (rng() & 1) ? 1 : -1);  // polar
      if (trial % 5 == 2) d = Eigen::Vector3d(-1, 0.01 * uni(rng), uni(rng));         // the seam
      const Eigen::Vector3d p = d.normalized() * R * alt(rng);
      for (const core::Chart* chart : {static_cast<const core::Chart*>(ll.get()),
                                       static_cast<const core::Chart*>(opaque.get())}) {
        const core::GridPoint c = edit::nearestVertex(*chart, p);
        ASSERT_TRUE(c.u >= 0 && c.u < m && c.v >= 0 && c.v <= m) << c.u << "," << c.v;
        if (c.v == 0 || c.v == m) {
          ASSERT_EQ(c.u, 0) << "a pole is returned as u = 0";
        }
        double best = -INFINITY;
        for (int v = 0; v <= m; ++v) {
          for (int u = 0; u <= m; ++u) best = std::max(best, edit::nearness(*chart, u, v, p));
        }
        const double got = edit::nearness(*chart, c.u, c.v, p);
        ASSERT_GE(got, best - 1e-9 * std::abs(best)) << chart->name() << " trial " << trial;
      }
    }
  }
}

TEST(EditControlVertex, SeamAndPolesAreCanonical) {
  auto chart = testkit::earthChart(6);
  const int m = chart->grid().m();
  const double R = testkit::kEarthRadius;
  EXPECT_EQ(edit::nearestVertex(*chart, {0, 0, 2 * R}), (core::GridPoint{0, m}));
  EXPECT_EQ(edit::nearestVertex(*chart, {1e-3, 0, -R}), (core::GridPoint{0, 0}));
  EXPECT_EQ(edit::nearestVertex(*chart, {-R, 1e-9, 0}),
            (core::GridPoint{0, m / 2}));  // longitude +-180
  EXPECT_EQ(edit::nearestVertex(*chart, {-R, -1e-9, 0}), (core::GridPoint{0, m / 2}));
  EXPECT_EQ(edit::nearestVertex(*chart, {1e-3, 0, 3e-4}),
            (edit::nearestVertex(*chart, {R, 0, 0.3 * R})))
      << "1 mm from the centre: only the direction counts";
  EXPECT_EQ(edit::nearestVertex(*chart, {1e300, 0, 0}), (core::GridPoint{m / 2, m / 2}));
}

TEST(EditControlVertex, RejectsTheCentreAndNonFinitePoints) {
  auto chart = testkit::earthChart(5);
  auto expectError = [&](const Eigen::Vector3d& p, const std::string& word) {
    try {
      (void)edit::nearestVertex(*chart, p);
      FAIL() << "accepted " << p.transpose();
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expectError({0, 0, 0}, "centre");
  expectError({NAN, 0, 1}, "not finite");
  expectError({0, INFINITY, 1}, "inf");
}

TEST(EditRegion, FromRectangleAddsTwinsAndWholePoleRows) {
  const core::GridSize g(5);
  const int m = g.m();
  const Region r =
      Region::fromRectangle({-3, 2, 0, 4}, g, true, true);  // across the seam, at the pole
  EXPECT_EQ(r.vBegin(), 0);
  EXPECT_EQ(r.vEnd(), 4);
  for (int u = 0; u <= m; ++u) EXPECT_TRUE(r.contains(u, 0)) << "pole row whole";
  for (int v = 1; v <= 4; ++v) {
    for (int u = 0; u <= m; ++u) {
      EXPECT_EQ(r.contains(u, v), u <= 2 || u >= m - 3) << u << "," << v;
    }
  }
  EXPECT_EQ(r.vertexCount(), std::size_t(m + 1) + 4u * 7u);
  EXPECT_EQ(r.pointCount(), 1u + 4u * 6u);
  const Region twin = Region::fromRectangle({m, m, 7, 7}, g, true, true);  // only u = m named
  EXPECT_TRUE(twin.contains(0, 7));
  EXPECT_EQ(twin.vertexCount(), 2u);
  EXPECT_EQ(twin.pointCount(), 1u);
  const Region flat = Region::fromRectangle({-3, 2, 0, 1}, g, false, false);  // no seam: clipped
  EXPECT_EQ(flat.vertexCount(), 2u * 3u);
  EXPECT_FALSE(flat.contains(m, 1));
}
