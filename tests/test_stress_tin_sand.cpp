// The sand TIN under many random stamps (all radii, from a few rims across to a third of the
// region, overlapping and at the border's edge), each followed by erosion and the removal of
// flat vertices: CGAL's own validity check holds, nothing is NaN, the volume is kept, and
// stamping one spot over and over does not grow the TIN. 600 stamps in CI (150 under ASan);
// PS_STRESS_SCALE=k runs k times as many.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <random>
#include <string>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/sand_grid.hpp"
#include "sand/tin_sand.hpp"
#include "sand/tin_sand_tool.hpp"
#include "stress_util.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

namespace {

using ps::sand::TinSand;
using ps::sand::TinStampTool;

ps::tin::DynamicTin randomTin(int n, double side, std::mt19937& rng) {
  std::uniform_real_distribution<double> noise(-0.05, 0.05);
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = side * i / (n - 1), y = side * j / (n - 1);
      points.emplace_back(x, y, 2.0 + 0.5 * std::sin(0.9 * x) * std::cos(0.6 * y) + noise(rng));
    }
  return ps::tin::DynamicTin(points);
}

// The tool's smallest valid radius on the chart, within 1 %, into r (`largest` must be valid).
// Call it inside ASSERT_NO_FATAL_FAILURE.
void smallestValidRadius(const ps::core::Chart& chart, double largest, double& r) {
  ps::sand::TinSandToolSettings settings;
  const auto valid = [&](double radius) {
    settings.radius = radius;
    try {
      settings.validate(&chart);
      return true;
    } catch (const ps::core::InputError&) {
      return false;
    }
  };
  r = largest;
  ASSERT_TRUE(valid(largest)) << largest << " m";
  while (valid(r * 0.99)) r *= 0.99;
}

// Begins the stroke at `input` (first) or moves it there, adding the stamps made to k. Where it
// stamped (`stamped`), the stroke's TIN is valid and the volume kept to 1e-9 of the planet's
// sum of A |h| (the largest such drift in worstDrift). Call it inside ASSERT_NO_FATAL_FAILURE.
void strokeTo(ps::edit::EditPipeline& pipe, ps::sand::TinSandTool& tool,
              const ps::terrain::Terrain& t, const ps::sand::SandGrid& grid,
              const ps::edit::ToolInput& input, bool first, const std::string& where, int& k,
              bool& stamped, double& worstDrift) {
  const double vBefore = grid.volume(t.heights());
  const std::size_t stampsBefore = tool.stamps();
  if (first) {
    pipe.beginStroke(tool, input);
  } else {
    pipe.moveTo(input);
  }
  k += int(tool.stamps() - stampsBefore);
  stamped = tool.stamps() != stampsBefore;
  if (!stamped) return;
  ASSERT_NE(tool.strokeTin(), nullptr) << "stamp " << k;
  ASSERT_EQ(tool.strokeTin()->sand().tin().validityProblem(), "")
      << "stamp " << k << " at " << where;
  const double drift = std::abs(grid.volume(t.heights()) - vBefore) / grid.absVolume(t.heights());
  worstDrift = std::max(worstDrift, drift);
  ASSERT_LE(drift, 1e-9) << "stamp " << k << " at " << where;
}

TEST(StressTinSand, RandomStampsKeepTheTriangulationValidAndTheVolume) {
  std::mt19937 rng(2026);
  const double side = 20.0;
  TinSand sand(randomTin(41, side, rng));
  const double v0 = sand.tin().volume();
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int stamps = 600 / (ps::testkit::underAsan() ? 4 : 1) * ps::testkit::stressScale();
  std::size_t done = 0, refused = 0, most = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < stamps; ++k) {
    const double r = 0.05 * std::pow(60.0, uni(rng));  // 0.05 .. 3 m, log-uniform
    const TinStampTool tool = TinStampTool::disc(r, 3 + int(uni(rng) * 40));
    // Centres over the whole region: some tools reach past its border and must be refused.
    const Eigen::Vector2d c(uni(rng) * side, uni(rng) * side);
    const double depth = 0.5 * r * uni(rng);
    try {
      sand.stamp(c, sand.tin().heightAt(c) - depth, tool);
      ++done;
    } catch (const ps::core::InputError&) {
      ++refused;
      continue;
    }
    for (int s = 0; s < 2; ++s) sand.erode();
    sand.removeRedundant();
    most = std::max(most, sand.tin().vertexCount());
    if (stamps >= 5000 && (k + 1) % (stamps / 20) == 0)
      std::cerr << "flat stress: " << k + 1 << " of " << stamps << " stamps, "
                << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                << " s, " << sand.tin().vertexCount() << " vertices, " << sand.activeCount()
                << " in Le\n";
    if (k % 100 == 0) {
      ASSERT_EQ(sand.tin().validityProblem(), "") << "after stamp " << k;
    }
  }
  ASSERT_TRUE(sand.tin().isValid());
  EXPECT_GT(done, std::size_t(stamps) / 2);
  EXPECT_GT(refused, 0u) << "tools past the border were tried";
  for (const double h : sand.tin().toTin().h) ASSERT_TRUE(std::isfinite(h));
  EXPECT_LE(std::abs(sand.tin().volume() - v0) / v0, 1e-9);
  RecordProperty("stamps", int(done));
  RecordProperty("most_vertices", int(most));
}

TEST(StressTinSand, OneSpotStampedOverAndOverStaysTheSameSize) {
  std::mt19937 rng(7);
  TinSand sand(randomTin(21, 10.0, rng));
  const TinStampTool tool = TinStampTool::disc(1.2, 32);
  std::size_t afterTen = 0, most = 0;
  const int stamps = 400 * ps::testkit::stressScale();
  for (int k = 0; k < stamps; ++k) {
    sand.stamp({5.0, 5.0}, 1.5, tool);
    for (int s = 0; s < 4; ++s) sand.erode();
    sand.removeRedundant();
    if (k == 9) afterTen = sand.tin().vertexCount();
    if (k >= 10) most = std::max(most, sand.tin().vertexCount());
  }
  EXPECT_LE(most, afterTen + 4 * tool.outline.size()) << "after ten stamps " << afterTen;
  EXPECT_TRUE(sand.tin().isValid());
}

// The tool on a small planet: short strokes (one to seven stamps a quarter radius apart, so the
// region TIN made at a stroke's first stamp takes the next ones) at both poles, on the seam and
// at random points, every radius the tool accepts there, each stamp pressed a random depth: the
// region TIN passes CGAL's validity check after every stamp, the heights stay finite and seam
// twins and pole rows one value after every stamp, the grid's volume is kept, and the bounds equal
// a full rebuild at the end. 40 stamps in CI; PS_STRESS_SCALE=k runs k times as many (the 10^5 of
// docs/SAND.md: k = 2500).
TEST(StressTinSand, ToolOnAPlanetAtThePolesTheSeamAndRandomPoints) {
  const double R = 20e3;
  auto chart = ps::sandtest::sphereChart(8, R);
  ps::terrain::Terrain t(chart, ps::testkit::bumpyHeights(*chart, 3, 100.0));
  ps::edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  ps::sand::TinSandToolSettings settings;
  // The tool's valid radii on this grid: from two cells to a region of 2.5 radii reaching a
  // quarter of the planet's radius (the region shrinks to that).
  const double rMax = 0.25 * R / 2.5;
  double rMin = 0;
  ASSERT_NO_FATAL_FAILURE(smallestValidRadius(*chart, rMax, rMin));
  ASSERT_LT(rMin, rMax);
  const ps::sand::SandGrid grid(chart);
  std::mt19937 rng(27);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int stamps = 40 * ps::testkit::stressScale();
  double worstDrift = 0;
  const auto start = std::chrono::steady_clock::now();
  std::size_t reused = 0;
  int nextReport = stamps / 20;
  for (int k = 0; k < stamps;) {
    double lat = 0, lon = 0;
    switch (k % 4) {
      case 0:  // a pole, on it or next to it
        lat = (k % 8 == 0 ? 1 : -1) * (90.0 - 3.0 * uni(rng));
        lon = 360.0 * uni(rng);
        break;
      case 1:  // on the seam or just either side
        lat = -80.0 + 160.0 * uni(rng);
        lon = 180.0 + 4.0 * (uni(rng) - 0.5);
        break;
      default:  // anywhere (uniform on the sphere)
        lat = std::asin(2.0 * uni(rng) - 1.0) * 180.0 / M_PI;
        lon = 360.0 * uni(rng);
    }
    settings.radius = rMin + (rMax - rMin) * uni(rng);
    settings.segments = 3 + int(uni(rng) * 45);
    ps::sand::TinSandTool tool(chart, settings);
    // The stroke: up to three moves of half a radius (two stamps each at the tool's spacing) in
    // one direction (in degrees of latitude and longitude: shorter near a pole).
    const double heading = 2.0 * M_PI * uni(rng);
    const double stepDeg = 0.5 * settings.radius / R * 180.0 / M_PI;
    const int moves = int(uni(rng) * 4);
    for (int s = 0; s <= moves && k < stamps; ++s) {
      const double sLat = std::clamp(lat + s * stepDeg * std::cos(heading), -90.0, 90.0);
      const double sLon = lon + s * stepDeg * std::sin(heading);
      const double depth = 0.5 * settings.radius * uni(rng);
      const ps::edit::ToolInput input{ps::edittest::latLon(sLat, sLon, R + settings.radius - depth),
                                      0.0};
      const std::string where = std::to_string(sLat) + ", " + std::to_string(sLon);
      bool stamped = false;
      ASSERT_NO_FATAL_FAILURE(
          strokeTo(pipe, tool, t, grid, input, s == 0, where, k, stamped, worstDrift));
      if (!stamped) continue;
      if (stamps >= 10000 && k >= nextReport) {
        std::cerr << "planet stress: " << k << " of " << stamps << " stamps, "
                  << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                  << " s\n";
        nextReport += stamps / 20;
      }
      for (const float h : t.heights()) ASSERT_TRUE(std::isfinite(h)) << "after stamp " << k;
      ASSERT_TRUE(ps::edittest::consistentHeights(t)) << "after stamp " << k;
    }
    pipe.endStroke();
    reused += tool.stamps() - tool.tinsMade();
  }
  EXPECT_TRUE(ps::edittest::boundsEqualFullRebuild(t));
  RecordProperty("stamps", stamps);
  char drift[32];
  std::snprintf(drift, sizeof drift, "%.3g", worstDrift);
  RecordProperty("worst_drift", drift);
  // Strokes of several stamps must have stamped into their region TIN, not only made new ones.
  EXPECT_GT(reused, 0u);
  RecordProperty("stamps_into_a_kept_region", int(reused));
}

// The tool on the glued charts (issue 43): the same random strokes on the octahedral chart, a
// torus and a cylinder, half of them starting on a fold, a corner or a seam and moving across it
// (the grid continued there; on the cylinder away from its open rims, where a stamp reaching
// over the rim is refused as at a flat grid's border), every radius the tool accepts, each stamp
// pressed a random depth:
// the region TIN valid by CGAL's check, the grid's volume kept to 1e-9, heights finite and twins
// one height after every stamp, the bounds equal a full rebuild at the end. 40 stamps a chart in
// CI; PS_STRESS_SCALE=k runs k times as many.
TEST(StressTinSand, ToolOnTheGluedChartsAcrossFoldsAndSeams) {
  struct Case {
    std::shared_ptr<const ps::core::Chart> chart;
    double curvature;  // the surface's smallest radius of curvature
    bool openEnds;     // the cylinder's rims: strokes stay a quarter of its length from them
  };
  const std::vector<Case> cases{
      {std::make_shared<ps::core::OctahedralChart>(ps::core::GridSize(8), 20e3), 20e3, false},
      {std::make_shared<ps::core::TorusChart>(ps::core::GridSize(9), 20e3, 10e3), 10e3, false},
      {std::make_shared<ps::core::CylinderChart>(ps::core::GridSize(8), 5e3, 2 * M_PI * 5e3), 5e3,
       true}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.chart->name());
    ps::terrain::Terrain t(c.chart, ps::testkit::bumpyHeights(*c.chart, 5, 100.0));
    ps::edit::EditPipeline pipe(t);
    pipe.setUndoEnabled(false);
    ps::sand::TinSandToolSettings settings;
    const double rMax = 0.25 * c.curvature / 2.5;
    double rMin = 0;
    ASSERT_NO_FATAL_FAILURE(smallestValidRadius(*c.chart, rMax, rMin));
    const ps::sand::SandGrid grid(c.chart);
    const ps::core::Chart& chart = *c.chart;
    const int m = chart.grid().m();
    std::mt19937 rng(43);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const int stamps = 40 * ps::testkit::stressScale();
    std::size_t reused = 0;
    for (int k = 0; k < stamps;) {
      // Where the stroke starts: a side (u = 0 or m, v = 0 or m: a fold, a corner, a seam) every
      // other stroke, else anywhere.
      int u = int(uni(rng) * m + 0.5), v = int(uni(rng) * m + 0.5);
      if (c.openEnds) v = m / 4 + v / 2;
      if (k % 2 == 0) (uni(rng) < 0.5 || c.openEnds ? u : v) = uni(rng) < 0.5 ? 0 : m;
      settings.radius = rMin + (rMax - rMin) * uni(rng);
      settings.segments = 3 + int(uni(rng) * 45);
      ps::sand::TinSandTool tool(c.chart, settings);
      // Up to three moves of about half a radius in one grid direction, continued across a side.
      const double cell =
          (chart.position(chart.continued(u + 1, v).u, chart.continued(u + 1, v).v, 0.0) -
           chart.position(u, v, 0.0))
              .norm();
      const int step = std::max(1, int(0.5 * settings.radius / std::max(cell, 1.0)));
      const int du = int(uni(rng) * 3) - 1, dv = int(uni(rng) * 3) - 1;
      const int moves = int(uni(rng) * 4);
      for (int s = 0; s <= moves && k < stamps; ++s) {
        const ps::core::GridPoint p = chart.continued(u + s * step * du, v + s * step * dv);
        const double depth = 0.5 * settings.radius * uni(rng);
        const ps::edit::ToolInput input{
            chart.position(p.u, p.v, 0.0) + (settings.radius - depth) * chart.up(p.u, p.v), 0.0};
        const std::string where = "(" + std::to_string(p.u) + ", " + std::to_string(p.v) + ")";
        bool stamped = false;
        double worstDrift = 0;
        ASSERT_NO_FATAL_FAILURE(
            strokeTo(pipe, tool, t, grid, input, s == 0, where, k, stamped, worstDrift));
        if (!stamped) continue;
        ASSERT_TRUE(ps::edittest::consistentHeights(t)) << "after stamp " << k;
      }
      pipe.endStroke();
      reused += tool.stamps() - tool.tinsMade();
    }
    EXPECT_TRUE(ps::edittest::boundsEqualFullRebuild(t));
    EXPECT_GT(reused, 0u);
  }
}

}  // namespace
