// The TIN sand tool's persistent region TIN: the error-bounded generation of scattered points
// (every point within the tolerance, checked by brute force), a stroke's stamps reusing one TIN
// (fewer vertices than the all-points TIN the tool made per stamp before, its surface against
// that tool's measured), a stamp leaving the region making a new one, the grid's volume kept at
// every stamp, a region made stale by the grid changing under it, and replays bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <iostream>
#include <random>

#include "core/input_error.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/sand_grid.hpp"
#include "sand/stroke_tin.hpp"
#include "sand/tin_sand_tool.hpp"
#include "small_planet.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"
#include "tin/scattered_tin.hpp"

using namespace ps;

namespace {

TEST(ScatteredTin, EveryPointEndsWithinTheToleranceWithFewerVertices) {
  std::mt19937 rng(27);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), noise(-0.02, 0.02);
  // A disc of jittered lattice points (a region of a planet's grid seen in its tangent plane).
  std::vector<Eigen::Vector3d> points;
  for (int j = -40; j <= 40; ++j)
    for (int i = -40; i <= 40; ++i) {
      const double x = i + jitter(rng), y = j + jitter(rng);
      if (x * x + y * y > 40.0 * 40.0) continue;
      points.emplace_back(x, y, 3.0 * std::sin(0.15 * x) * std::cos(0.1 * y) + noise(rng));
    }
  std::size_t lastVertices = points.size();
  for (const double tolerance : {0.03, 0.1, 0.5}) {
    tin::ScatteredTinReport report;
    const tin::DynamicTin tin = tin::errorBoundedTin(points, 1.0, tolerance, &report);
    ASSERT_TRUE(tin.isValid()) << tin.validityProblem();
    double worst = 0;
    for (const Eigen::Vector3d& p : points) {
      const double h = tin.heightAt(p.head<2>());
      ASSERT_TRUE(std::isfinite(h)) << p.transpose() << " outside the TIN's domain";
      worst = std::max(worst, std::abs(h - p.z()));
    }
    EXPECT_LE(worst, tolerance) << "brute force over every point";
    EXPECT_EQ(worst, report.maxError);
    EXPECT_LT(report.vertices, lastVertices) << "a looser tolerance, fewer vertices";
    EXPECT_LT(report.repaired, report.vertices / 2) << "the export's generation picks most";
    lastVertices = report.vertices;
    std::cout << "tolerance " << tolerance << ": " << report.vertices << " vertices of "
              << points.size() << " points (" << report.startVertices
              << " from the lattice and the hull, " << report.repaired << " repaired in "
              << report.repairRounds << " rounds)\n";
  }
  EXPECT_THROW(tin::errorBoundedTin(points, 1.0, 0.0), core::InputError);
  EXPECT_THROW(tin::errorBoundedTin(points, -1.0, 0.1), core::InputError);
}

sand::TinSandToolSettings toolSettings(double radius) {
  sand::TinSandToolSettings s;
  s.radius = radius;

  return s;
}

// The tool as it was before the region TIN: every grid point, a TIN per stamp, 3 radii.
sand::TinSandToolSettings perStampSettings(double radius) {
  sand::TinSandToolSettings s = toolSettings(radius);
  s.regionRadius = 3.0;
  s.tolerance = 0;
  s.persistent = false;
  return s;
}

using testkit::aboveSmallPlanet;
using testkit::SmallPlanet;

// A stroke along the parallel at `lat` from `lon0` over `degrees`, the tool's lowest point
// `press` under the reference surface plus 100 m, a sample every 0.2 degrees.
void stroke(edit::EditPipeline& pipe, const sand::TinSandTool& tool, double lat, double lon0,
            double degrees, double press, const std::function<void()>& afterSample = {}) {
  const double r = tool.settings().radius;
  pipe.beginStroke(tool, {aboveSmallPlanet(lat, lon0, r - press), 0.0});
  if (afterSample) afterSample();
  for (double d = 0.2; d <= degrees + 1e-9; d += 0.2) {
    pipe.moveTo({aboveSmallPlanet(lat, lon0 + d, r - press), 0.0});
    if (afterSample) afterSample();
  }
  pipe.endStroke();
}

TEST(TinSandTool, AStrokesStampsReuseOneRegionTinKeepingTheVolume) {
  SmallPlanet p;
  const sand::SandGrid grid(p.chart);
  sand::TinSandTool tool(p.chart, toolSettings(1200.0));
  std::size_t stamps = 0;
  double worstDrift = 0;
  double volume = grid.volume(p.t.heights());
  // 2 degrees of longitude at 10 N: 690 m, 0.58 radii, 2 stamps.
  stroke(p.pipe, tool, 10.0, 30.0, 2.0, 300.0, [&] {
    const double v = grid.volume(p.t.heights());
    worstDrift = std::max(worstDrift, std::abs(v - volume) / grid.absVolume(p.t.heights()));
    volume = v;
    ++stamps;
  });
  EXPECT_EQ(tool.tinsMade(), 1u) << "one region TIN for the whole stroke";
  EXPECT_LE(worstDrift, 1e-9);
  EXPECT_TRUE(edittest::consistentHeights(p.t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(p.t));
  const auto& s = tool.lastStats();
  EXPECT_FALSE(s.madeTin);
  EXPECT_LE(s.generation.maxError, 1e-3 * 1200.0) << "the generation's bound at the grid points";
  std::cout << "region: " << s.gridVertices << " grid points, TIN made with "
            << s.generation.vertices << " vertices (error " << s.generation.maxError << " m), "
            << s.tinVertices << " after the stroke\n";
}

struct Difference {
  double rms = 0, worst = 0;
  std::size_t changed = 0;
};

// The heights of a and b over the grid entries either changed.
Difference differ(const SmallPlanet& a, const SmallPlanet& b) {
  Difference d;
  const auto start = testkit::bumpyHeights(*a.chart, 3, 100.0);
  const auto& ha = a.t.heights();
  const auto& hb = b.t.heights();
  double sum2 = 0;
  for (std::size_t k = 0; k < ha.size(); ++k) {
    if (ha[k] == start[k] && hb[k] == start[k]) continue;
    const double e = double(ha[k]) - double(hb[k]);
    d.worst = std::max(d.worst, std::abs(e));
    sum2 += e * e;
    ++d.changed;
  }
  d.rms = std::sqrt(sum2 / double(std::max<std::size_t>(d.changed, 1)));
  return d;
}

// One stamp, no erosion: the region TIN (coarse, but every grid point within the stamp's reach)
// presses what the all-points TIN pressed.
TEST(TinSandTool, OneStampOnTheRegionTinPressesWhatTheAllPointsTinPressed) {
  SmallPlanet a(10), b(10);  // 1025^2, 123 m cells: 10 a radius
  sand::TinSandToolSettings sa = toolSettings(1200.0), sb = perStampSettings(1200.0);
  sa.erosionSteps = sb.erosionSteps = 0;
  sand::TinSandTool region(a.chart, sa), perStamp(b.chart, sb);
  a.pipe.apply(region, {aboveSmallPlanet(-20.0, 100.0, 900.0), 0.0});
  b.pipe.apply(perStamp, {aboveSmallPlanet(-20.0, 100.0, 900.0), 0.0});
  EXPECT_LT(region.lastStats().tinVertices, perStamp.lastStats().tinVertices);
  const Difference d = differ(a, b);
  std::cout << "one stamp, no erosion: region TIN " << region.lastStats().tinVertices
            << " vertices, all-points " << perStamp.lastStats().tinVertices << "; heights over "
            << d.changed << " entries differ by " << d.rms << " m RMS, " << d.worst
            << " m at most (press 300 m)\n";
  EXPECT_GT(d.changed, 1000u);
  EXPECT_LT(d.rms, 0.5);
  EXPECT_LT(d.worst, 5.0);
}

TEST(TinSandTool, AStrokesRegionTinIsSmallerThanThePerStampTinsAndMeasuredAgainstThem) {
  SmallPlanet a(10), b(10);
  sand::TinSandTool region(a.chart, toolSettings(1200.0));
  sand::TinSandTool perStamp(b.chart, perStampSettings(1200.0));
  std::size_t perStampLargest = 0;
  stroke(a.pipe, region, -20.0, 100.0, 4.0, 300.0);
  stroke(b.pipe, perStamp, -20.0, 100.0, 4.0, 300.0,
         [&] { perStampLargest = std::max(perStampLargest, perStamp.lastStats().tinVertices); });
  EXPECT_EQ(region.tinsMade(), 1u);
  EXPECT_EQ(perStamp.tinsMade(), 5u);
  EXPECT_LT(region.lastStats().tinVertices, perStampLargest);
  // The two differ by more than one stamp does: the region TIN keeps each imprint's crisp wall
  // for the next stamp and its erosion's active list, where the per-stamp TIN starts from the
  // grid's heights, which hold the wall at the grid's spacing.
  const Difference d = differ(a, b);
  std::cout << "stroke: region TIN " << region.lastStats().tinVertices << " vertices ("
            << region.tinsMade() << " made) against the per-stamp TINs' largest " << perStampLargest
            << " (" << perStamp.tinsMade() << " made); heights over " << d.changed
            << " entries differ by " << d.rms << " m RMS, " << d.worst
            << " m at most (press 300 m)\n";
  EXPECT_GT(d.changed, 1000u);
}

TEST(TinSandTool, AStampLeavingTheRegionMakesANewOne) {
  SmallPlanet p;
  const sand::SandGrid grid(p.chart);
  sand::TinSandTool tool(p.chart, toolSettings(1200.0));
  const double v0 = grid.volume(p.t.heights());
  std::size_t stamps = 0;
  // 30 degrees at the equator: 10.5 km, 8.7 radii, 35 stamps.
  stroke(p.pipe, tool, 0.0, 170.0, 30.0, 300.0, [&] { ++stamps; });
  std::cout << stamps << " samples, " << tool.tinsMade() << " region TINs\n";
  EXPECT_GT(tool.tinsMade(), 1u);
  EXPECT_LT(tool.tinsMade(), 8u) << "stamps reuse a region while inside it";
  EXPECT_LE(std::abs(grid.volume(p.t.heights()) - v0) / grid.absVolume(p.t.heights()), 1e-9);
  EXPECT_TRUE(edittest::consistentHeights(p.t)) << "across the seam";
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(p.t));
}

TEST(TinSandTool, ARegionIsStaleOnceTheGridChangesUnderIt) {
  SmallPlanet p;
  const sand::TinSandToolSettings s = toolSettings(1200.0);
  edit::RegionGrower grower;
  edit::DistanceField field(p.chart);
  const core::GridPoint c{40, 100};
  field.setCentre(c);
  edit::Region F;
  grower.grow(field, 5 * 1200.0, F);
  std::vector<float> h(p.t.heights().begin(), p.t.heights().end());
  const sand::StrokeTin region(*p.chart, h, F, c, 1.2, s.sand);
  EXPECT_TRUE(region.holds(h));
  const auto& q = region.points()[region.points().size() / 2];
  h[p.chart->grid().index(q.u, q.v)] += 1e-3f;
  EXPECT_FALSE(region.holds(h));
}

std::vector<float> strokes(bool oneTool) {
  SmallPlanet p;
  sand::TinSandTool first(p.chart, toolSettings(1200.0));
  sand::TinSandTool second(p.chart, toolSettings(1200.0));
  stroke(p.pipe, first, 60.0, 10.0, 6.0, 300.0);
  // The second stroke starts where the first ended: a tool that kept the first stroke's TIN
  // would give another surface than a fresh one.
  stroke(p.pipe, oneTool ? first : second, 60.0, 16.0, 6.0, 200.0);
  p.pipe.undo();
  stroke(p.pipe, oneTool ? first : second, 60.0, 15.0, 6.0, 250.0);
  return {p.t.heights().begin(), p.t.heights().end()};
}

TEST(TinSandTool, StrokesReplayBitForBitWhicheverToolInstanceRunsThem) {
  const auto a = strokes(true), b = strokes(true), c = strokes(false);
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float)));
}

}  // namespace
