// The sand TIN (paper 000) and the changing triangulation under it: random stamps, erosion and
// removals, then the invariants (a valid triangulation, nothing NaN, the volume kept), and what
// each part must do on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/input_error.hpp"
#include "sand/tin_sand.hpp"
#include "tin/dynamic_tin.hpp"
#include "tin/tin_check.hpp"

namespace {

using ps::sand::TinSand;
using ps::sand::TinSandSettings;
using ps::sand::TinStampTool;
using ps::tin::DynamicTin;

// A side x side grid of points `spacing` apart with heights from f(x, y).
template <class F>
DynamicTin gridTin(int side, double spacing, F&& f) {
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const double x = i * spacing, y = j * spacing;
      points.emplace_back(x, y, f(x, y));
    }
  return DynamicTin(points);
}

double maxEdgeSlope(const DynamicTin& tin) {
  double worst = 0;
  std::vector<DynamicTin::Vertex> nb;
  for (const auto v : tin.vertices()) {
    tin.neighbours(v, nb);
    for (const auto u : nb)
      worst = std::max(worst, std::abs(tin.height(u) - tin.height(v)) /
                                  (tin.position(u) - tin.position(v)).norm());
  }
  return worst;
}

double relative(double a, double b) {
  return std::abs(a - b) / std::abs(b);
}

TEST(DynamicTin, ThePlaneVolumeIsExactAndSurvivesInsertionAndRemoval) {
  // V of a plane over [0, 10]^2: its mean height times the area.
  const auto plane = [](double x, double y) { return 2.0 + 0.3 * x - 0.1 * y; };
  DynamicTin tin = gridTin(11, 1.0, plane);
  EXPECT_NEAR(tin.volume(), 100.0 * plane(5, 5), 1e-11);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> in(0.5, 9.5);
  for (int k = 0; k < 200; ++k) tin.insertOnSurface({in(rng), in(rng)});
  EXPECT_NEAR(tin.volume(), 100.0 * plane(5, 5), 1e-10) << "on a plane flips change nothing";
  for (const auto v : tin.vertices())
    if (!tin.onHull(v) && v % 3 == 0) {
      EXPECT_TRUE(tin.remove(v));
    }
  EXPECT_NEAR(tin.volume(), 100.0 * plane(5, 5), 1e-10);
  EXPECT_TRUE(tin.isValid());
  const ps::tin::Tin out = tin.toTin();
  const ps::tin::MeshTopology top = ps::tin::meshTopology(out.xy.size(), out.triangles);
  EXPECT_EQ(top.euler(), 1);
  EXPECT_EQ(top.nonManifoldEdges, 0u);
}

TEST(DynamicTin, RemovalPutsBackTheVolumeItsNewTrianglesChange) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> z(-1.0, 1.0);
  DynamicTin tin = gridTin(15, 0.5, [&](double, double) { return z(rng); });
  const double v0 = tin.volume();
  std::size_t changed = 0;
  for (const auto v : tin.vertices()) {
    if (tin.onHull(v)) {
      EXPECT_FALSE(tin.remove(v)) << "hull vertices stay";
      continue;
    }
    double change = 0;
    ASSERT_TRUE(tin.remove(v, &change));
    changed += change != 0;
  }
  EXPECT_GT(changed, 10u) << "rough heights: re-filling changes the volume";
  EXPECT_LE(relative(tin.volume(), v0), 1e-12);
  EXPECT_TRUE(tin.isValid());
}

TEST(DynamicTin, ConstraintsKeepTheirGenerationAndAreFreedNearAStamp) {
  DynamicTin tin = gridTin(21, 1.0, [](double x, double) { return 0.1 * x; });
  const auto a = tin.insertOnSurface({5.25, 5.25}), b = tin.insertOnSurface({14.75, 5.25});
  tin.constrain(a, b, 7);
  EXPECT_GE(tin.constrainedEdgeCount(), 1u);
  EXPECT_TRUE(tin.isValid()) << "every constrained edge carries a generation";
  // A vertex inserted onto the constrained edge splits it; both halves keep generation 7.
  const auto mid = tin.insertOnSurface({8.0, 5.25});
  EXPECT_EQ(tin.generation(mid, a) == 7 || tin.generation(mid, b) == 7, true);
  EXPECT_TRUE(tin.isValid());
  EXPECT_GT(tin.freeConstraintsNear({10.0, 5.0}, 1.0), 0u);
  EXPECT_TRUE(tin.isValid());
  EXPECT_LT(tin.constrainedEdgeCount(), 3u);
}

TEST(DynamicTin, DeeperThanAnswersAsDepthInsideDoesForEveryPoint) {
  // Random point sets (their border a convex hull of any shape), then points inside, on and
  // outside it in grid order and at random: the batch answer equals the point-by-point one.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Vector3d> pts;
    const int n = 3 + int(rng() % 400);
    const double sx = 1.0 + 40.0 * std::abs(uni(rng)), sy = 1.0 + 40.0 * std::abs(uni(rng));
    for (int i = 0; i < n; ++i) pts.emplace_back(sx * uni(rng), sy * uni(rng), uni(rng));
    const DynamicTin tin(pts);
    std::vector<Eigen::Vector2d> queries;
    for (int y = -60; y <= 60; ++y) {
      for (int x = -60; x <= 60; ++x) queries.emplace_back(0.8 * x, 0.8 * y);
    }
    for (int i = 0; i < 2000; ++i) queries.emplace_back(50.0 * uni(rng), 50.0 * uni(rng));
    for (const auto& p : pts) queries.emplace_back(p.x(), p.y());  // on the border, some
    for (double depth : {1e-3, 0.5, 2.0, 7.5, 100.0}) {
      const std::vector<std::uint8_t> deep = tin.deeperThan(queries, depth);
      ASSERT_EQ(deep.size(), queries.size());
      int inside = 0;
      for (std::size_t i = 0; i < queries.size(); ++i) {
        ASSERT_EQ(deep[i] != 0, tin.depthInside(queries[i]) >= depth)
            << "trial " << trial << " depth " << depth << " point " << queries[i].transpose();
        inside += deep[i];
      }
      if (depth == 0.5 && n > 50) {
        EXPECT_GT(inside, 0) << "trial " << trial;
      }
    }
  }
}

TEST(TinSand, AStampPressesItsBottomKeepsTheVolumeAndLeavesACrispWall) {
  TinSand sand(gridTin(41, 0.25, [](double, double) { return 1.0; }));
  const double v0 = sand.tin().volume();
  const TinStampTool tool = TinStampTool::disc(1.5);
  const auto stats = sand.stamp({5.0, 5.0}, 0.6, tool);
  EXPECT_GT(stats.pressed, 0u);
  // A 0.4 m deep 24-gon and its wall (the older vertices on it removed, the wall is the
  // contours' triangles: half the rim's ring of the depth).
  const double polygon = 12 * 1.5 * 1.5 * std::sin(2 * M_PI / 24);
  const double wall = 0.5 * (polygon * (1.05 * 1.05 - 1.0));
  EXPECT_NEAR(stats.displacedVolume, 0.4 * (polygon + wall), 0.01) << "a 0.4 m deep 24-gon";
  EXPECT_GT(stats.removedWall, 0u) << "the grid's vertices on the wall";
  EXPECT_LE(relative(sand.tin().volume(), v0), 1e-12);
  EXPECT_DOUBLE_EQ(sand.tin().heightAt({5.0, 5.0}), 0.6);
  EXPECT_DOUBLE_EQ(sand.tin().heightAt({5.0 + 1.4, 5.0}), 0.6);
  // The wall: from the bottom to above the old surface within the rim (5 % of the radius).
  EXPECT_GT(sand.tin().heightAt({5.0 + 1.5 + 0.075, 5.0}), 1.0);
  EXPECT_GT(maxEdgeSlope(sand.tin()), 3.0) << "a wall far steeper than the talus";
  EXPECT_TRUE(sand.tin().isValid());
}

TEST(TinSand, APressOnlyStampLeavesTheToolsShapeAndPushesNothingAside) {
  TinSand sand(gridTin(41, 0.25, [](double, double) { return 1.0; }));
  const double v0 = sand.tin().volume();
  TinStampTool tool = TinStampTool::disc(1.5);
  tool.pushAside = false;
  const auto stats = sand.stamp({5.0, 5.0}, 0.6, tool);
  EXPECT_LE(stats.inserted, 2 * tool.outline.size()) << "the two contours, no rampart rings";
  EXPECT_NEAR(sand.tin().volume(), v0 - stats.displacedVolume, 1e-12 * v0);
  EXPECT_GT(stats.displacedVolume, 0.4 * 12 * 1.5 * 1.5 * std::sin(2 * M_PI / 24));
  EXPECT_DOUBLE_EQ(sand.tin().heightAt({5.0, 5.0}), 0.6);
  // Beyond the outer contour the sand is as it was: nothing pushed aside.
  for (const double dx : {1.6, 2.0, 3.0})
    EXPECT_DOUBLE_EQ(sand.tin().heightAt({5.0 + dx, 5.0}), 1.0);
  // On the wall, halfway across the rim (a corner's ray), half the depth.
  EXPECT_NEAR(sand.tin().heightAt({5.0 + 1.5 * 1.025, 5.0}), 0.8, 1e-9);
  EXPECT_TRUE(sand.tin().isValid());
}

TEST(TinSand, ErosionSettlesEveryEdgeToTheTalusAndKeepsTheVolume) {
  TinSandSettings settings;
  settings.removeRedundant = false;
  TinSand sand(gridTin(41, 0.25, [](double, double) { return 1.0; }), settings);
  const double v0 = sand.tin().volume();
  sand.stamp({5.0, 5.0}, 0.2, TinStampTool::disc(1.5));
  int steps = 0;
  while (sand.activeCount() > 0 && steps < 20000) sand.erode(), ++steps;
  EXPECT_EQ(sand.activeCount(), 0u) << "came to rest in " << steps << " steps";
  const double tanTalus = settings.material.tanTalus();
  EXPECT_LE(maxEdgeSlope(sand.tin()), tanTalus * (1 + settings.material.talusTolerance) + 1e-9);
  EXPECT_LE(relative(sand.tin().volume(), v0), 1e-11);
  EXPECT_TRUE(sand.tin().isValid());
}

TEST(TinSand, RandomStampsErosionAndRemovalKeepEveryInvariant) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  TinSand sand(gridTin(33, 0.5, [&](double x, double y) {
    return 2.0 + 0.3 * std::sin(x) * std::cos(0.7 * y) + 0.02 * uni(rng);
  }));
  const double v0 = sand.tin().volume();
  std::size_t removed = 0;
  for (int k = 0; k < 150; ++k) {
    const double r = 0.3 + 2.0 * uni(rng);
    const TinStampTool tool = TinStampTool::disc(r, 6 + int(uni(rng) * 30));
    const Eigen::Vector2d c(tool.reach() + uni(rng) * (16 - 2 * tool.reach()),
                            tool.reach() + uni(rng) * (16 - 2 * tool.reach()));
    if (!(c.x() > tool.reach() && c.x() < 16 - tool.reach())) continue;
    sand.stamp(c, sand.tin().heightAt(c) - 0.3 * uni(rng), tool);
    for (int s = 0; s < 5; ++s) sand.erode();
    removed += sand.removeRedundant();
    ASSERT_TRUE(sand.tin().isValid()) << "after stamp " << k;
  }
  EXPECT_LE(relative(sand.tin().volume(), v0), 1e-10);
  EXPECT_GT(removed, 0u);
  for (const double h : sand.tin().toTin().h) ASSERT_TRUE(std::isfinite(h));
}

TEST(TinSand, StampingOneSpotAgainAndAgainKeepsTheVertexCountBounded) {
  TinSand sand(gridTin(21, 0.5, [](double, double) { return 1.0; }));
  const TinStampTool tool = TinStampTool::disc(1.0);
  sand.stamp({5.0, 5.0}, 0.8, tool);
  for (int s = 0; s < 20; ++s) sand.erode();
  sand.removeRedundant();
  const std::size_t first = sand.tin().vertexCount();
  std::size_t most = first;
  for (int k = 0; k < 200; ++k) {
    sand.stamp({5.0, 5.0}, 0.8, tool);
    for (int s = 0; s < 5; ++s) sand.erode();
    sand.removeRedundant();
    most = std::max(most, sand.tin().vertexCount());
  }
  EXPECT_LE(most, first + 3 * tool.outline.size()) << "first " << first;
  EXPECT_TRUE(sand.tin().isValid());
}

TEST(TinSand, OlderConstraintsInsideANewStampAreDropped) {
  TinSand sand(gridTin(41, 0.25, [](double, double) { return 1.0; }));
  sand.stamp({4.0, 5.0}, 0.7, TinStampTool::disc(1.0));
  const std::size_t afterFirst = sand.tin().constrainedEdgeCount();
  EXPECT_GE(afterFirst, 48u) << "two contours of 24 edges";
  const auto stats = sand.stamp({4.8, 5.0}, 0.7, TinStampTool::disc(1.0));
  EXPECT_GT(stats.freedConstraints, 0u);
  // No constrained edge of the first stamp comes within the second's outer contour.
  const ps::tin::Tin t = sand.tin().toTin();
  std::vector<DynamicTin::Vertex> ids = sand.tin().vertices();
  for (const auto a : ids)
    for (const auto b : ids) {
      if (a >= b || sand.tin().generation(a, b) != 1) continue;
      const Eigen::Vector2d pa = sand.tin().position(a), pb = sand.tin().position(b);
      const Eigen::Vector2d mid = 0.5 * (pa + pb);
      EXPECT_GT(
          std::min({(pa - Eigen::Vector2d(4.8, 5)).norm(), (pb - Eigen::Vector2d(4.8, 5)).norm(),
                    (mid - Eigen::Vector2d(4.8, 5)).norm()}),
          1.0);
    }
  EXPECT_TRUE(sand.tin().isValid());
}

TEST(TinSand, BadToolsAndSettingsAreRefusedAndTheSurfaceStays) {
  TinSand sand(gridTin(21, 0.5, [](double x, double) { return 1.0 + 0.01 * x; }));
  const double v0 = sand.tin().volume();
  const std::size_t n0 = sand.tin().vertexCount();
  TinStampTool crossing = TinStampTool::disc(1.0, 4);
  std::swap(crossing.outline[1], crossing.outline[2]);  // a bow tie
  TinStampTool repeated = TinStampTool::disc(1.0, 8);
  repeated.outline[3] = repeated.outline[4];
  TinStampTool clockwise = TinStampTool::disc(1.0, 8);
  std::reverse(clockwise.outline.begin(), clockwise.outline.end());
  const auto refuses = [&](const TinStampTool& tool, const Eigen::Vector2d& c,
                           const std::string& says) {
    try {
      sand.stamp(c, 0.5, tool);
      ADD_FAILURE() << "accepted; expected: " << says;
    } catch (const ps::core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refuses(crossing, {5, 5}, "intersects itself");
  refuses(repeated, {5, 5}, "degenerate");
  refuses(clockwise, {5, 5}, "counter-clockwise");
  refuses(TinStampTool::disc(4.0), {5, 5}, "beyond the TIN's region");
  refuses(TinStampTool::disc(20.0), {5, 5}, "beyond the TIN's region");
  EXPECT_EQ(sand.tin().vertexCount(), n0);
  EXPECT_EQ(sand.tin().volume(), v0);
  TinSandSettings bad;
  bad.material.talusDeg = 95;
  EXPECT_THROW(TinSand(gridTin(5, 1.0, [](double, double) { return 0.0; }), bad),
               ps::core::InputError);
  bad = {};
  bad.flatDeg = 0;
  EXPECT_THROW(TinSand(gridTin(5, 1.0, [](double, double) { return 0.0; }), bad),
               ps::core::InputError);
}

}  // namespace
