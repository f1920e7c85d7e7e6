// The semi-implicit (LOD) diffusion scheme on the glued charts (the octahedral chart, both
// mappings; the torus; the cylinder): lines continued across the folds and seams (docs/SAND.md,
// "Semi-implicit diffusion on the glued charts").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "core/cylinder_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "sand/sand_field.hpp"
#include "test_sand_util.hpp"

using namespace ps;

namespace {

struct PileCase {
  std::string name;
  std::shared_ptr<const core::Chart> chart;
  double pileRadius;                   // m: a few cells
  std::vector<core::GridPoint> spots;  // folds, cone points, seams, corners, rims
};

// 65^2 grids: a 1 km octahedral planet (cells of about 40 m), the tubes' tests' torus (R = 4 km,
// r = 1.5 km) and cylinder (R = 2 km, L = 8 km).
std::vector<PileCase> pileCases() {
  using Mapping = core::OctahedralChart::Mapping;
  const core::GridSize g(6);
  const int m = g.m();
  const std::vector<core::GridPoint> octaSpots = {{0, 0},     {0, m / 4}, {m / 2, 0},
                                                  {0, m / 2}, {m, m / 2}, {m / 2, m},
                                                  {m, m},     {m / 4, 0}, {m / 2, m / 2}};
  return {
      {"octahedral equal area",
       std::make_shared<core::OctahedralChart>(g, 1000.0, Mapping::kEqualArea), 150.0, octaSpots},
      {"octahedral central", std::make_shared<core::OctahedralChart>(g, 1000.0, Mapping::kCentral),
       150.0, octaSpots},
      {"torus",
       std::make_shared<core::TorusChart>(g, 4000.0, 1500.0),
       700.0,
       {{0, 0}, {0, m / 3}, {m / 3, 0}, {m / 2, m / 2}, {m / 4, m / 4}}},
      {"cylinder",
       std::make_shared<core::CylinderChart>(g, 2000.0, 8000.0),
       500.0,
       {{0, m / 2}, {m / 3, 0}, {0, m}, {m / 2, m / 2}, {m / 5, 1}}},
  };
}

// A cone of height `top` (m) and `radius` (m) about spot p's point: every twin gets its height.
std::vector<float> pileAt(const core::Chart& chart, core::GridPoint p, double radius, double top) {
  const core::GridSize g = chart.grid();
  const Eigen::Vector3d c = chart.position(p.u, p.v, 0.0);
  std::vector<float> h(g.count());
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const double r = (chart.position(u, v, 0.0) - c).norm() / radius;
      h[g.index(u, v)] = float(r < 1.0 ? top * (1.0 - r) : 0.0);
    }
  }
  return h;
}

// Largest |h(u, v) - h(canonical(u, v))| over the grid.
double twinSpread(const core::Chart& chart, const std::vector<double>& h) {
  const core::GridSize g = chart.grid();
  double worst = 0.0;
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const core::GridPoint c = chart.canonical(u, v);
      worst = std::max(worst, std::abs(h[g.index(u, v)] - h[g.index(c.u, c.v)]));
    }
  }
  return worst;
}

}  // namespace

// Random materials, piles on every spot, dt from half the explicit bound to 1000 times it:
// volume kept, finite, the range kept (a maximum principle), twins one value, material moved
// across the folds and seams; the step over the marked cells equals the whole grid's bit for bit.
TEST(SandGluedImplicit, RandomSettingsKeepVolumeRangeAndTwinsAtAnyStep) {
  std::mt19937 rng(4301);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double factors[3] = {0.5, 30.0, 1000.0};
  double worstDrift = 0.0;
  for (const PileCase& c : pileCases()) {
    for (std::size_t s = 0; s < c.spots.size(); ++s) {
      sand::Material mat = sand::Material::sand();
      mat.diffusion = 0.2 + 2.0 * uni(rng);
      mat.reposeDeg = 20.0 + 20.0 * uni(rng);
      mat.cohesion = uni(rng) < 0.3 ? 2.0 * uni(rng) : 0.0;
      // Sides of 45-63 degrees, steeper than the angle of repose.
      const double radius = c.pileRadius * (1.0 + uni(rng)), top = radius * (1.0 + uni(rng));
      const double factor = factors[s % 3];
      auto h = pileAt(*c.chart, c.spots[s], radius, top);
      auto h2 = h;
      sand::SandField a(c.chart, h), b(c.chart, h2);
      // a: the pile's cells marked (the active set grows across the folds and seams); b: all.
      sandtest::markNonZero(a, *c.chart, h);
      const double v0 = a.volume(), scale = sandtest::absVolume(a);
      const double dt = factor * a.explicitBound(mat);
      ASSERT_TRUE(std::isfinite(dt) && dt > 0.0);
      const std::string what =
          c.name + " spot " + std::to_string(s) + " dt x" + std::to_string(factor);
      EXPECT_TRUE(sandtest::diffusionSideBySide(a, b, mat, dt, sand::DiffusionScheme::kSemiImplicit,
                                                sand::StepPolicy::kClamp, 25))
          << what;
      std::vector<double> ha;
      a.copyHeights(ha);
      EXPECT_TRUE(sandtest::allFinite(a)) << what;
      const double drift = std::abs(a.volume() - v0) / scale;
      worstDrift = std::max(worstDrift, drift);
      EXPECT_LE(drift, 1e-12) << what;
      const auto [lo, hi] = std::minmax_element(ha.begin(), ha.end());
      EXPECT_GE(*lo, 0.0) << what;
      EXPECT_LE(*hi, double(float(top))) << what;
      EXPECT_EQ(twinSpread(*c.chart, ha), 0.0) << what;
      // The pile spread: the top came down and some cell that was bare got sand.
      EXPECT_LT(*hi, double(float(top))) << what;
      int gained = 0;
      for (std::size_t i = 0; i < ha.size(); ++i) gained += (h[i] == 0.0f && ha[i] > 0.0) ? 1 : 0;
      EXPECT_GT(gained, 0) << what;
    }
  }
  std::printf("semi-implicit on the glued charts: volume drift at most %.3g\n", worstDrift);
}

// One semi-implicit step of a small dt equals one explicit step to O(dt^2): the difference falls
// 4x when dt halves (a link missing or counted twice in the lines would leave an O(dt) term:
// 2x), and is below 2 % of the step's change. Rough random heights, so every link is active.
TEST(SandGluedImplicit, ASmallStepEqualsTheExplicitStep) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const sand::Material mat = sand::Material::sand();
  for (const PileCase& c : pileCases()) {
    const std::vector<float> h0 = sandtest::twinNoise(*c.chart, [&] { return 400.0 * uni(rng); });
    double diff[2] = {0, 0}, change[2] = {0, 0};
    double bound = 0.0;
    for (int half = 0; half < 2; ++half) {
      auto he = h0, hi = h0;
      sand::SandField e(c.chart, he), s(c.chart, hi);
      bound = e.explicitBound(mat);
      const double dt = 0.02 * bound / (half ? 2.0 : 1.0);
      e.markAll();
      s.markAll();
      e.diffusionStep(mat, dt, sand::DiffusionScheme::kExplicit, sand::StepPolicy::kRefuse);
      s.diffusionStep(mat, dt, sand::DiffusionScheme::kSemiImplicit);
      std::vector<double> xe, xs;
      e.copyHeights(xe);
      s.copyHeights(xs);
      for (std::size_t i = 0; i < xe.size(); ++i) {
        diff[half] = std::max(diff[half], std::abs(xe[i] - xs[i]));
        change[half] = std::max(change[half], std::abs(xe[i] - double(h0[i])));
      }
    }
    std::printf(
        "%s: explicit vs semi-implicit at dt = bound/50: %.3g m of a %.3g m change; "
        "at dt/2: %.3g m (ratio %.2f)\n",
        c.name.c_str(), diff[0], change[0], diff[1], diff[0] / diff[1]);
    EXPECT_GT(change[0], 0.0) << c.name;
    EXPECT_LT(diff[0], 0.02 * change[0]) << c.name;
    EXPECT_GT(diff[0] / diff[1], 3.5) << c.name;
    EXPECT_LT(diff[0] / diff[1], 4.5) << c.name;
  }
}

// A push force with the semi-implicit scheme, on a fold and on the south pole's corners of the
// octahedral chart, the torus's corner and the cylinder's seam at a rim: volume kept, a rut
// under the tool on both sides of the fold or seam, the marked step equal to the whole grid's.
TEST(SandGluedImplicit, APushForceAcrossAFoldOrSeamKeepsVolume) {
  for (const PileCase& c : pileCases()) {
    const int m = c.chart->grid().m();
    const bool octahedral = c.name.rfind("octahedral", 0) == 0;
    const std::vector<core::GridPoint> where =
        octahedral ? std::vector<core::GridPoint>{{0, m / 4}, {0, 0}}
                   : std::vector<core::GridPoint>{{0, c.name == "torus" ? 0 : m / 2}};
    for (const core::GridPoint p : where) {
      const std::string what = c.name + " " + std::to_string(p.u) + "," + std::to_string(p.v);
      const sandtest::PushCase push{.at = p,
                                    .radius = 1.5 * c.pileRadius,
                                    .scheme = sand::DiffusionScheme::kSemiImplicit,
                                    .boundFactor = 30.0,
                                    .steps = 10,
                                    .volumeTolerance = 1e-12};
      sandtest::pushTheLayer(
          c.chart, push, what, [&](const sand::SandField& a, const sand::SandField&) {
            std::vector<double> ha;
            a.copyHeights(ha);
            EXPECT_EQ(twinSpread(*c.chart, ha), 0.0) << what;
            // Both sides of the fold or seam moved: (1, v) and, across it, (1, m - v) on the
            // octahedral chart, (m - 1, v) on a tube.
            EXPECT_NE(a.height(1, p.v), 10.0) << what;
            const core::GridPoint across =
                octahedral ? core::GridPoint{1, m - p.v} : core::GridPoint{m - 1, p.v};
            EXPECT_NE(a.height(across.u, across.v), 10.0) << what;
          });
    }
  }
}
