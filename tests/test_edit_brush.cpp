#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using edit::BrushMode;
using edit::BrushSettings;
using edit::GaussianBrush;
using edit::GaussianProfile;

namespace {

// Paper 003's equation 7.
double paperGaussian(double x, double sigma, double mu) {
  return std::exp(-(x - mu) * (x - mu) / (2 * sigma * sigma)) /
         (sigma * std::sqrt(2 * std::numbers::pi));
}

}  // namespace

TEST(EditBrush, ProfileIsThePaperGaussianShiftedToZeroAtTheBorder) {
  const double r = 300e3;
  for (double sigma : {0.17, 0.75, 0.3}) {
    for (double mu : {1.0, 0.8, 1.5}) {
      const GaussianProfile p(r, sigma, mu);
      const double g0 = paperGaussian(0, sigma, mu), g1 = paperGaussian(1, sigma, mu);
      for (int i = 0; i <= 100; ++i) {
        const double d = r * i / 100.0;
        const double expected = (paperGaussian(1 - d / r, sigma, mu) - g0) / (g1 - g0);
        ASSERT_NEAR(p(d), std::max(0.0, expected), 1e-12 * (1 + std::abs(expected)))
            << sigma << " " << mu << " " << d;
      }
      EXPECT_NEAR(p(0), 1.0, 1e-15);
      EXPECT_EQ(p(r), 0.0);
      if (mu >= 1.0) {  // maximum at the control vertex, falling to the border
        for (int i = 1; i <= 100; ++i) ASSERT_LE(p(r * i / 100.0), p(r * (i - 1) / 100.0));
      }
    }
  }
  // sigma = 0.75 without the shift would leave a step of 41 % at the border.
  EXPECT_NEAR(paperGaussian(0, 0.75, 1) / paperGaussian(1, 0.75, 1), 0.41, 0.005);
}

TEST(EditBrush, RejectsBadSettingsNamingTheValue) {
  struct Case {
    BrushSettings s;
    std::string expect;
  };
  std::vector<Case> cases;
  auto with = [](auto f) {
    BrushSettings s;
    f(s);
    return s;
  };
  cases.push_back({with([](BrushSettings& s) { s.radius = 0; }), "r_d = 0"});
  cases.push_back({with([](BrushSettings& s) { s.radius = -5; }), "r_d = -5"});
  cases.push_back({with([](BrushSettings& s) { s.radius = NAN; }), "r_d = nan"});
  cases.push_back({with([](BrushSettings& s) { s.radius = INFINITY; }), "r_d = inf"});
  cases.push_back({with([](BrushSettings& s) { s.sigma = 0; }), "sigma = 0"});
  cases.push_back({with([](BrushSettings& s) { s.sigma = -0.2; }), "sigma = -0.2"});
  cases.push_back({with([](BrushSettings& s) { s.sigma = NAN; }), "sigma = nan"});
  cases.push_back({with([](BrushSettings& s) { s.mu = 0.5; }), "mu = 0.5"});
  cases.push_back({with([](BrushSettings& s) { s.strength = -1; }), "strength = -1"});
  cases.push_back({with([](BrushSettings& s) { s.target = NAN; }), "target = nan"});
  cases.push_back({with([](BrushSettings& s) { s.spacing = 0; }), "spacing = 0"});
  cases.push_back({with([](BrushSettings& s) { s.spacing = 2; }), "spacing = 2"});
  for (const Case& c : cases) {
    try {
      c.s.validate();
      FAIL() << "accepted, expected " << c.expect;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(BrushSettings{}.validate());
}

TEST(EditBrush, RaiseLowerAndSet) {
  auto t = testkit::levelTerrain(7);
  edit::EditPipeline pipe(t);
  const auto g = t.grid();
  const int m = g.m();
  const double R = testkit::kEarthRadius;
  BrushSettings s;
  s.radius = 800e3;
  s.strength = 500;
  GaussianBrush brush(s);
  const Eigen::Vector3d at = t.chart().position(m / 4, m / 2 + 3, 0.0);
  const auto rep = pipe.apply(brush, {at, 0});
  const auto c = rep.control;
  EXPECT_EQ(c, (core::GridPoint{m / 4, m / 2 + 3}));
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 500.0f);
  // Heights follow the profile of the distance on the sphere; zero outside V_d.
  const GaussianProfile prof(s.radius, s.sigma, s.mu);
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const double d2 = pipe.field().distance2(u, v);
      const float expected =
          d2 <= s.radius * s.radius ? float(500.0 * prof.fromDistance2(d2)) : 0.0f;
      ASSERT_EQ(t.height(u, v), expected) << u << "," << v;
    }
  }
  s.mode = BrushMode::kLower;
  s.strength = 200;
  brush.setSettings(s);
  pipe.apply(brush, {at * 3, 0});  // altitude does not matter
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 300.0f);
  // Set: move toward 100 m by at most 1000 m * shape.
  s.mode = BrushMode::kSet;
  s.target = 100;
  s.strength = 1000;
  brush.setSettings(s);
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  pipe.apply(brush, {at, 0});
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 100.0f);
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const double d2 = pipe.field().distance2(u, v);
      const double w = d2 <= s.radius * s.radius ? 1000.0 * prof.fromDistance2(d2) : 0.0;
      const double old = before[g.index(u, v)];
      const float expected = float(old + std::clamp(100.0 - old, -w, w));
      ASSERT_EQ(t.height(u, v), expected) << u << "," << v;
    }
  }
  (void)R;
}

TEST(EditBrush, RateModeScalesWithDt) {
  auto t = testkit::levelTerrain(6);
  edit::EditPipeline pipe(t);
  const int m = t.grid().m();
  BrushSettings s;
  s.radius = 900e3;
  s.rate = true;
  s.strength = 100;  // m/s
  GaussianBrush brush(s);
  const Eigen::Vector3d at = t.chart().position(7, 20, 0.0);
  const auto c = pipe.apply(brush, {at, 0.5}).control;
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 50.0f);
  pipe.apply(brush, {at, 2.0});
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 250.0f);
  const std::vector<float> before(t.heights().begin(), t.heights().end());
  const auto revision = t.revision();
  const auto still = pipe.apply(brush, {at, 0.0});
  EXPECT_TRUE(edittest::sameBits(t.heights(), before)) << "dt = 0 changes nothing";
  EXPECT_TRUE(still.dirty.empty());
  EXPECT_EQ(t.revision(), revision) << "nothing to commit";
  // Elsewhere in V_d the change scales with dt too.
  const int u = (c.u + 2) % m, v = c.v + 1;
  const float h1 = t.height(u, v);
  pipe.apply(brush, {at, 1.0});
  const float h2 = t.height(u, v);
  pipe.apply(brush, {at, 3.0});
  EXPECT_NEAR(double(t.height(u, v)) - h2, 3.0 * (double(h2) - h1), 1e-3);
}

TEST(EditBrush, ClampsToTheHeightLimit) {
  auto t = testkit::levelTerrain(6);
  edit::EditPipeline pipe(t);
  BrushSettings s;
  s.radius = 2000e3;
  s.strength = 1e9;
  GaussianBrush brush(s);
  const auto c =
      pipe.apply(brush, {testkit::kEarthRadius * Eigen::Vector3d(0.3, 0.5, 0.7).normalized(), 0})
          .control;
  EXPECT_EQ(t.height(c.u, c.v), edit::floatAtMost(t.heightLimit()));
  s.mode = BrushMode::kLower;
  s.strength = 1e30;
  brush.setSettings(s);
  pipe.apply(brush, {testkit::kEarthRadius * Eigen::Vector3d(0.3, 0.5, 0.7).normalized(), 0});
  EXPECT_EQ(t.height(c.u, c.v), -edit::floatAtMost(t.heightLimit()));
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_NO_THROW(terrain::Terrain::validateHeights(t.chart(), t.heights()));
}

TEST(EditBrush, GenericChartPathAgreesWithTheLatLongPath) {
  auto ll = testkit::earthChart(6);
  auto opaque = std::make_shared<edittest::OpaqueChart>(ll);
  const auto heights = testkit::bumpyHeights(*ll, 3, 3000.0);
  terrain::Terrain a(ll, heights), b(opaque, heights);
  edit::EditPipeline pa(a), pb(b);
  std::mt19937 rng(4);
  BrushSettings s;
  s.strength = 700;
  for (int i = 0; i < 12; ++i) {
    const core::GridPoint c = edittest::randomCentre(rng, ll->grid().m());
    s.radius = 200e3 + 1e6 * (i % 4);
    s.sigma = (i & 1) ? 0.75 : 0.17;
    GaussianBrush brush(s);
    const Eigen::Vector3d p = ll->position(c.u, c.v, 0.0);
    const auto ra = pa.apply(brush, {p, 0});
    const auto rb = pb.apply(brush, {p, 0});
    ASSERT_EQ(ra.control, rb.control);
    ASSERT_EQ(ra.modifiedVertices, rb.modifiedVertices);
  }
  for (std::size_t k = 0; k < heights.size(); ++k)
    ASSERT_NEAR(a.heights()[k], b.heights()[k], 1e-2) << k;
  EXPECT_TRUE(edittest::consistentHeights(b));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(b));
}

// The pipeline hands the brush the distances region growing computed: they are the field's own
// bits, so the brush leaves the same heights as when it computes every distance again, on a
// chart with folds (octahedral), with a seam glued beyond it (torus), with rims (cylinder) and
// with a seam and pole rows (lat-long through the generic path); and they hold every vertex of
// the region.
TEST(EditBrush, RegionGrowingsDistancesAreTheOnesTheBrushWouldCompute) {
  const std::vector<std::shared_ptr<const core::Chart>> charts{
      testkit::octahedralChart(7),
      std::make_shared<core::TorusChart>(core::GridSize(7), 4.5e6, 1.8e6),
      std::make_shared<core::CylinderChart>(core::GridSize(7), 3e6, 6e6),
      std::make_shared<edittest::OpaqueChart>(testkit::earthChart(7))};
  std::mt19937 rng(8);
  for (const auto& chart : charts) {
    const auto heights = testkit::bumpyHeights(*chart, 5, 2000.0);
    terrain::Terrain piped(chart, heights), computed(chart, heights);
    edit::EditPipeline pipe(piped);
    edit::DistanceField field(chart);
    edit::RegionGrower grower;
    edit::Region region;
    const double size = chart->sphereRadius() > 0 ? chart->sphereRadius() : 3e6;
    for (int i = 0; i < 16; ++i) {
      const core::GridPoint c = edittest::randomCentre(rng, chart->grid().m());
      BrushSettings s;
      s.radius = size * (0.02 + 0.3 * (i % 5) / 4.0);
      s.strength = 900;
      s.mode = (i & 1) ? BrushMode::kRaise : BrushMode::kLower;
      const GaussianBrush brush(s);
      const Eigen::Vector3d p = chart->position(c.u, c.v, 0.0);
      const auto rep = pipe.apply(brush, {p, 0});
      // The same stamp, every distance computed by the field.
      field.setCentre(rep.control);
      grower.grow(field, s.radius, region);
      const edit::ToolContext ctx{computed,    field,  region,
                                  rep.control, {p, 0}, edit::floatAtMost(computed.heightLimit())};
      ASSERT_EQ(ctx.distances, nullptr);
      auto h = computed.mutableHeights();
      const terrain::VertexBox dirty = brush.apply(ctx, h);
      ASSERT_TRUE(dirty.uBegin == rep.dirty.uBegin && dirty.uEnd == rep.dirty.uEnd &&
                  dirty.vBegin == rep.dirty.vBegin && dirty.vEnd == rep.dirty.vEnd)
          << chart->name() << ", stamp " << i;
      for (std::size_t k = 0; k < heights.size(); ++k)
        ASSERT_EQ(piped.heights()[k], computed.heights()[k]) << chart->name() << ", stamp " << i;
      // Every vertex of the region has its distance kept, bit for bit the field's.
      const edit::RowDistanceBlocks* kept = grower.distances();
      ASSERT_NE(kept, nullptr);
      std::vector<double> got, want;
      // The first row that differs, then no more (an ASSERT would end only the lambda).
      testing::AssertionResult rowsKept = testing::AssertionSuccess();
      region.forEachSpan([&](int v, int a, int b) {
        if (!rowsKept) return;
        got.resize(std::size_t(b - a + 1)), want.resize(got.size());
        if (!kept->copy(v, a, b, got.data())) {
          rowsKept = testing::AssertionFailure()
                     << "row " << v << " [" << a << ", " << b << "] not kept";
          return;
        }
        field.rowDistances2(v, a, b, want.data());
        const auto differ = std::mismatch(got.begin(), got.end(), want.begin());
        if (differ.first != got.end())
          rowsKept = testing::AssertionFailure()
                     << "vertex (" << a + (differ.first - got.begin()) << ", " << v
                     << "): kept distance^2 " << *differ.first << ", the field's "
                     << *differ.second;
      });
      ASSERT_TRUE(rowsKept) << chart->name() << ", stamp " << i;
    }
  }
}

TEST(EditBrush, ExtremeButValidSettingsNeverProduceNaN) {
  auto t = testkit::levelTerrain(6, 10.0f);
  edit::EditPipeline pipe(t);
  const Eigen::Vector3d at = t.chart().position(11, 40, 0.0);
  std::vector<BrushSettings> list;
  BrushSettings s;
  s.radius = 5e5;
  s.mu = 0.6;  // a ring profile: shape far above 1 inside with a tiny sigma
  s.sigma = 1e-3;
  s.strength = 1e300;
  list.push_back(s);
  s.rate = true;  // strength * dt overflows
  list.push_back(s);
  s.rate = false;
  s.mode = BrushMode::kLower;
  s.sigma = 1e6;
  s.mu = 1e6;
  list.push_back(s);
  s.mode = BrushMode::kSet;
  s.target = -1e300;
  s.radius = 1e-3;  // the smallest radius: only the control vertex
  list.push_back(s);
  s.radius = 1e300;  // the whole planet
  s.target = 7;
  list.push_back(s);
  for (const BrushSettings& b : list) {
    pipe.apply(GaussianBrush(b), {at, 1e10});
    ASSERT_TRUE(edittest::consistentHeights(t));
  }
  EXPECT_FLOAT_EQ(t.height(0, 0), 7.0f);
  BrushSettings tiny;
  tiny.radius = 1e-4;
  EXPECT_THROW(tiny.validate(), core::InputError);
}
