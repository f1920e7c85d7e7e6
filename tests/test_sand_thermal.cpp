#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include "core/input_error.hpp"
#include "sand/sand_field.hpp"
#include "sand/sand_grid.hpp"
#include "test_sand_util.hpp"

using namespace ps;
using sandtest::flatChart;
using sandtest::heightsFrom;
using sandtest::settle;
using sandtest::sphereChart;

namespace {

double relDrift(double before, double after, double scale) {
  return std::abs(after - before) / scale;
}

}  // namespace

TEST(SandGrid, SphereCellAreasSumToTheSphereAndFlatCellsToTheTile) {
  for (int n : {5, 8, 11}) {
    const double R = 6372790.0;
    sand::SandGrid g(sphereChart(n, R));
    double total = 2 * g.area(0);
    for (int v = 1; v < g.m(); ++v) total += g.m() * g.area(v);
    EXPECT_NEAR(total / (4 * std::numbers::pi * R * R), 1.0, 1e-12) << n;
    EXPECT_EQ(g.area(0), g.area(g.m()));
    EXPECT_EQ(g.area(1), g.area(g.m() - 1));
    // The pole link is the meridian spacing; a ring cell's horizontal chord is tiny.
    EXPECT_EQ(g.vertical(0), g.vertical(g.m() / 2));
    EXPECT_LT(g.horizontal(1), g.horizontal(g.m() / 2));
  }
  sand::SandGrid flat(flatChart(5, 2.0, 3.0));
  EXPECT_EQ(flat.area(0), 6.0);
  EXPECT_EQ(flat.columns(), 33);
  EXPECT_EQ(flat.diagonal(4), std::hypot(2.0, 3.0));
  EXPECT_THROW(sand::SandGrid(nullptr), core::InputError);
}

TEST(SandThermal, PileSettlesToTheTalusAngleKeepsVolumeAndRests) {
  auto chart = flatChart(6);
  auto h = heightsFrom(*chart, [](int u, int v) { return (u == 32 && v == 32) ? 40.0 : 0.0; });
  sand::SandField f(chart, h);
  const sand::Material mat = sand::Material::sand();
  const double v0 = f.volume();
  f.mark({30, 34, 30, 34});
  const int steps = settle(f, mat, 20000);
  EXPECT_TRUE(f.atRest()) << steps;
  EXPECT_EQ(f.pendingTiles(), 0u);
  EXPECT_LE(sandtest::worstTalusExcess(f, mat), mat.talusTolerance * (1 + 1e-9));
  EXPECT_LE(relDrift(v0, f.volume(), 40.0), 1e-13);
  // At rest a step visits nothing.
  const sand::StepReport r = f.thermalStep(mat);
  EXPECT_EQ(r.cells, 0u);
  EXPECT_FALSE(r.moved);
  // The pile spread: the centre came down, the volume is all there.
  EXPECT_LT(f.height(32, 32), 40.0);
  EXPECT_GT(f.height(32, 32), 0.0);
}

TEST(SandThermal, VolumeDriftAfter10000StepsIsBelow1e9OnFlatAndSphere) {
  for (bool sphere : {false, true}) {
    std::shared_ptr<const core::Chart> chart;
    if (sphere) {
      chart = sphereChart(5, 1000.0);  // cells of about 100 m
    } else {
      chart = flatChart(5, 1.0, 1.0);
    }
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> noise(0.0, 1.0);
    const double amp = sphere ? 400.0 : 8.0;
    auto h = heightsFrom(*chart, [&](int u, int v) {
      double x = 100.0 + amp * noise(rng);
      if (sphere && v >= 28) x += 3.0 * amp;      // a pile on the north pole
      if (sphere && (u < 2 || u > 29)) x += amp;  // and a ridge along the seam
      return x;
    });
    sand::SandField f(chart, h);
    sand::Material mat = sand::Material::sand();
    mat.talusDeg = 3.0;  // slow: keeps most of the grid moving for thousands of steps
    mat.talusTolerance = 1e-6;
    f.markAll();
    const double v0 = f.volume();
    const double scale = sand::SandGrid(chart).absVolume(h);
    int moving = 0;
    for (int i = 0; i < 10000; ++i) moving += f.thermalStep(mat).moved ? 1 : 0;
    EXPECT_GT(moving, 500) << "sphere " << sphere;
    EXPECT_LE(relDrift(v0, f.volume(), scale), 1e-9) << "sphere " << sphere;
    EXPECT_TRUE(sandtest::allFinite(f));
    std::ostringstream drift;
    drift << relDrift(v0, f.volume(), scale);
    RecordProperty(sphere ? "sphere_drift" : "flat_drift", drift.str());
  }
}

TEST(SandThermal, ActiveSetStepEqualsWholeGridStepBitForBit) {
  // A terrain at rest (a slope below the talus) with a crater dug into it: settling only from
  // the marked crater must give, step by step, exactly what stepping every cell gives.
  for (bool sphere : {false, true}) {
    std::shared_ptr<const core::Chart> chart =
        sphere ? std::shared_ptr<const core::Chart>(sphereChart(6, 1000.0)) : flatChart(6);
    const int m = chart->grid().m();
    const int cu = sphere ? 1 : 33, cv = sphere ? m - 3 : 30;  // sphere: at the seam, by a pole
    auto h = heightsFrom(*chart, [&](int u, int v) {
      double x = sphere ? 0.0 : 0.2 * u;
      const int du = std::min(std::abs(u - cu), m - std::abs(u - cu));
      if (du * du + (v - cv) * (v - cv) <= 9) x -= sphere ? 300.0 : 20.0;
      if (sphere && v == m) x -= 400.0;
      return x;
    });
    auto h2 = h;
    sand::SandField a(chart, h), b(chart, h2);
    const sand::Material mat = sand::Material::sand();
    a.mark({cu - 5, cu + 5, cv - 5, std::min(m, cv + 5)});
    ASSERT_NO_FATAL_FAILURE(
        sandtest::thermalSideBySide(a, b, mat, 150, sphere ? "sphere" : "flat"));
    const int more = settle(a, mat, 20000);
    EXPECT_TRUE(a.atRest()) << "sphere " << sphere << " after " << more << " more steps";
    EXPECT_LE(sandtest::worstTalusExcess(a, mat), mat.talusTolerance * (1 + 1e-9));
  }
}

TEST(SandThermal, ThreadCountDoesNotChangeTheResult) {
  auto chart = flatChart(8);  // 81 tiles: enough for the steps to run in parallel
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(0.0, 30.0);
  auto h = heightsFrom(*chart, [&](int, int) { return noise(rng); });
  auto h2 = h;
  sand::SandField a(chart, h), b(chart, h2);
  a.markAll();
  b.markAll();
  const int threads = omp_get_max_threads();
  const sand::Material mat = sand::Material::sand();
  omp_set_num_threads(1);
  for (int i = 0; i < 8; ++i) a.thermalStep(mat);
  omp_set_num_threads(std::max(2, threads));
  for (int i = 0; i < 8; ++i) b.thermalStep(mat);
  omp_set_num_threads(threads);
  std::vector<double> ha, hb;
  a.copyHeights(ha);
  b.copyHeights(hb);
  EXPECT_EQ(std::memcmp(ha.data(), hb.data(), ha.size() * sizeof(double)), 0);
}

TEST(StressSand, ThermalNoNaNAfter1e5StepsAtTheLargestRate) {
  // c = 1 (the largest accepted rate) on extreme noise, kicked again every 25000 steps: heights
  // stay finite and inside the initial range (the step obeys a maximum principle).
  sand::Material mat = sand::Material::sand();
  mat.erosionRate = 1.0;
  mat.talusDeg = 45.0;
  EXPECT_TRUE(
      sandtest::kickedNoiseKeepsItsRange(11, 1e4, [&](sand::SandField& f) { f.thermalStep(mat); }));
}

TEST(SandThermal, PileOnAPoleSettlesAndThePoleRowStaysOnePoint) {
  auto chart = sphereChart(5, 1000.0);
  const int m = 32;
  auto h = heightsFrom(*chart, [&](int, int v) { return v == m ? 800.0 : 0.0; });
  sand::SandField f(chart, h);
  const sand::Material mat = sand::Material::sand();
  f.mark({0, m, m - 1, m});
  const double v0 = f.volume();
  const int steps = settle(f, mat, 20000);
  EXPECT_TRUE(f.atRest()) << steps;
  EXPECT_LE(sandtest::worstTalusExcess(f, mat), mat.talusTolerance * (1 + 1e-9));
  EXPECT_LE(relDrift(v0, f.volume(), 800.0 * sand::SandGrid(chart).area(m)), 1e-12);
  EXPECT_LT(f.height(0, m), 800.0);
  // The ring around the pole received material evenly (the pole neighbours all m of them).
  for (int u = 1; u < m; ++u) EXPECT_EQ(f.height(u, m - 1), f.height(0, m - 1)) << u;
  const auto dirty = f.writeBack(1e30);
  EXPECT_FALSE(dirty.empty());
  const core::GridSize g = chart->grid();
  for (int u = 0; u <= m; ++u) EXPECT_EQ(h[g.index(u, m)], h[g.index(0, m)]);
  for (int v = 0; v <= m; ++v) EXPECT_EQ(h[g.index(m, v)], h[g.index(0, v)]);
}

TEST(SandThermal, BadMaterialIsRefusedBeforeAnythingMoves) {
  auto chart = flatChart(5);
  auto h = heightsFrom(*chart, [](int u, int) { return 3.0 * u; });
  sand::SandField f(chart, h);
  f.markAll();
  for (double talus : {0.0, 90.0, -5.0, 120.0, std::nan("")}) {
    sand::Material mat;
    mat.talusDeg = talus;
    try {
      f.thermalStep(mat);
      ADD_FAILURE() << "talus " << talus << " accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("talus"), std::string::npos) << e.what();
    }
  }
  sand::Material fast;
  fast.erosionRate = 1.5;
  EXPECT_THROW(f.thermalStep(fast), core::InputError);
  EXPECT_EQ(f.height(10, 3), 30.0);
  EXPECT_EQ(f.pendingTiles(), 4u);  // still pending (2 x 2 tiles), nothing stepped
}
