#include <gtest/gtest.h>

#include "core/input_error.hpp"
#include "mesh_checks.hpp"
#include "terrain/error_mesher.hpp"
#include "terrain/screen_error.hpp"
#include "test_terrains.hpp"

using namespace ps;

TEST(ErrorMesher, TrueErrorNeverExceedsTheRequestAndMeshIsClosed) {
  for (auto rule : {terrain::ErrorRule::kWedgie, terrain::ErrorRule::kHybridExact}) {
    const auto t = testkit::bumpyTerrain(8, 12, 20000.0, rule);
    std::size_t previous = 0;
    for (double maxErr : {20000.0, 5000.0, 1000.0, 200.0}) {
      const auto mesh = terrain::meshToError(t, maxErr);
      const double trueErr = terrain::measureTrueError(t, mesh);
      EXPECT_LE(trueErr, maxErr) << terrain::toString(rule) << " at " << maxErr;
      EXPECT_EQ(testkit::conformityDefect(t, mesh), "");
      EXPECT_GT(mesh.triangleCount(), previous) << "a smaller error needs more triangles";
      previous = mesh.triangleCount();
    }
  }
}

TEST(ErrorMesher, HybridRuleNeedsNoMoreTrianglesThanWedgie) {
  auto chart = testkit::earthChart(8);
  const auto h = testkit::bumpyHeights(*chart, 21, 20000.0);
  const terrain::Terrain wedgie(chart, h, terrain::ErrorRule::kWedgie);
  const terrain::Terrain hybrid(chart, h, terrain::ErrorRule::kHybridExact);
  for (double maxErr : {3000.0, 500.0, 100.0}) {
    EXPECT_LE(terrain::meshToError(hybrid, maxErr).triangleCount(),
              terrain::meshToError(wedgie, maxErr).triangleCount())
        << maxErr;
  }
  EXPECT_THROW(terrain::meshToError(hybrid, -1), core::InputError);
}
