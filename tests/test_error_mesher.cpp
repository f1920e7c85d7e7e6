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

// A reused mesher and mesh (the export sweep's warm path) must give exactly what a fresh one
// gives, whatever was meshed before: coarser, finer, or another grid.
TEST(ErrorMesher, ReusedMesherAndMeshGiveTheFreshResult) {
  const auto small = testkit::bumpyTerrain(6, 3, 20000.0, terrain::ErrorRule::kHybridExact);
  const auto large = testkit::bumpyTerrain(8, 12, 20000.0, terrain::ErrorRule::kHybridExact);
  terrain::ErrorMesher mesher;
  terrain::Mesh reused;
  std::uint64_t generation = reused.generation;
  struct Step {
    const terrain::Terrain* t;
    double maxErr;
  };
  for (const Step& s : {Step{&large, 200.0}, Step{&large, 5000.0}, Step{&large, 100.0},
                        Step{&small, 1000.0}, Step{&large, 200.0}, Step{&small, 0.0}}) {
    mesher.mesh(*s.t, s.maxErr, reused);
    EXPECT_GT(reused.generation, generation) << "a refilled mesh must say it changed";
    generation = reused.generation;
    const terrain::Mesh fresh = terrain::meshToError(*s.t, s.maxErr);
    ASSERT_GT(fresh.triangleCount(), 0u);
    EXPECT_EQ(reused.indices, fresh.indices) << s.maxErr;
    EXPECT_EQ(reused.gridIndex, fresh.gridIndex) << s.maxErr;
    ASSERT_EQ(reused.positions.size(), fresh.positions.size());
    for (std::size_t i = 0; i < fresh.positions.size(); ++i)
      ASSERT_EQ(reused.positions[i], fresh.positions[i]) << i;
    EXPECT_EQ(reused.eye, Eigen::Vector3d::Zero());
  }
  // A refused request leaves the previous mesh as it was.
  const std::vector<std::uint32_t> before = reused.indices;
  EXPECT_THROW(mesher.mesh(small, std::nan(""), reused), core::InputError);
  EXPECT_EQ(reused.indices, before);
}
