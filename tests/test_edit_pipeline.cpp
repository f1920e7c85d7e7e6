#include <gtest/gtest.h>

#include <random>

#include "core/input_error.hpp"
#include "edit/brush.hpp"
#include "edit/control_vertex.hpp"
#include "edit/edit_pipeline.hpp"
#include "mesh_checks.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using edit::BrushMode;
using edit::BrushSettings;
using edit::GaussianBrush;

namespace {

BrushSettings randomBrush(std::mt19937& rng, double R, int m) {
  BrushSettings s;
  s.radius = edittest::randomRadius(rng, R, m);
  if (rng() % 3 == 0) s.radius = std::min(s.radius, 1.5e6);
  s.sigma = (rng() & 1) ? 0.17 : 0.75;
  s.mode = BrushMode(rng() % 3);
  s.strength = 50.0 + double(rng() % 4000);
  s.target = -2000.0 + double(rng() % 4000);
  return s;
}

// Every invariant an edit must keep, checked against the state before it.
void checkEdit(const terrain::Terrain& t, const edit::EditPipeline& pipe,
               const std::vector<float>& before, const std::string& what) {
  const auto g = t.grid();
  const edit::Region& region = pipe.lastRegion();
  // The dirty rectangle holds every changed vertex and is tight in v.
  const terrain::VertexBox& dirty = pipe.lastReport().dirty;
  std::vector<std::uint8_t> inDirty(g.count(), 0);
  dirty.forEachColumnRange(g, [&](int a, int b) {
    for (int v = dirty.vBegin; v <= dirty.vEnd; ++v) {
      for (int u = a; u <= b; ++u) inDirty[g.index(u, v)] = 1;
    }
  });
  int firstChanged = -1, lastChanged = -1;
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      if (std::memcmp(&before[g.index(u, v)], &t.heights()[g.index(u, v)], sizeof(float)) == 0)
        continue;
      ASSERT_TRUE(inDirty[g.index(u, v)])
          << what << ": changed (" << u << "," << v << ") outside " << dirty.describe();
      if (firstChanged < 0) firstChanged = v;
      lastChanged = v;
    }
  }
  if (firstChanged >= 0) {
    ASSERT_EQ(dirty.vBegin, firstChanged) << what;
    ASSERT_EQ(dirty.vEnd, lastChanged) << what;
  } else {
    ASSERT_TRUE(dirty.empty()) << what;
  }
  // Only V_d changes.
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      if (region.contains(u, v)) continue;
      ASSERT_EQ(std::memcmp(&before[g.index(u, v)], &t.heights()[g.index(u, v)], sizeof(float)), 0)
          << what << ": vertex (" << u << "," << v << ") outside V_d changed";
    }
  }
  ASSERT_TRUE(edittest::consistentHeights(t)) << what;
  ASSERT_TRUE(edittest::boundsEqualFullRebuild(t)) << what;
}

}  // namespace

TEST(EditPipeline, RandomEditsKeepEveryInvariant) {
  for (int n : {6, 7, 8}) {
    auto t = testkit::bumpyTerrain(n, 20 + n, 6000.0);
    edit::EditPipeline pipe(t);
    pipe.setUndoEnabled(false);
    const int m = t.grid().m();
    const double R = t.chart().sphereRadius();
    std::mt19937 rng(300 + n);
    const int edits = n == 8 ? 8 : 25;
    for (int i = 0; i < edits; ++i) {
      const BrushSettings s = randomBrush(rng, R, m);
      const core::GridPoint c = edittest::randomCentre(rng, m);
      // A tool tip near the vertex, at some altitude.
      const Eigen::Vector3d p =
          t.chart().position(c.u, c.v, 0.0) * (0.8 + 0.5 * double(rng() % 100) / 100);
      const std::vector<float> before(t.heights().begin(), t.heights().end());
      const auto rep = pipe.apply(GaussianBrush(s), {p, 0.0});
      const std::string what = "n=" + std::to_string(n) + " edit " + std::to_string(i);
      ASSERT_TRUE(edittest::equalsBruteForce(pipe.field(), s.radius, pipe.lastRegion())) << what;
      ASSERT_EQ(rep.modifiedVertices, pipe.lastRegion().vertexCount());
      ASSERT_EQ(rep.control, edit::nearestVertex(t.chart(), p));
      checkEdit(t, pipe, before, what);
    }
    // The mesh of the sculpted planet is still crack-free.
    terrain::Tessellator tess;
    terrain::TessellationSettings ts;
    ts.cull = false;
    ts.triangleBudget = 0;
    for (double distMax : {0.5, 4.0}) {
      ts.distMaxPx = distMax;
      const auto cam = terrain::Camera::lookAt({0.3 * R, -2.2 * R, 1.4 * R}, {0, 0, 0}, {0, 0, 1},
                                               640, 480, 1.0);
      const auto& mesh = tess.tessellate(t, cam, ts);
      ASSERT_GT(mesh.triangleCount(), 0u);
      ASSERT_EQ(testkit::conformityDefect(t, mesh), "") << "n=" << n;
    }
  }
}

TEST(EditPipeline, GenericChartEditsKeepEveryInvariant) {
  auto ll = testkit::earthChart(6);
  auto chart = std::make_shared<edittest::OpaqueChart>(ll);
  terrain::Terrain t(chart, testkit::bumpyHeights(*ll, 8, 5000.0));
  edit::EditPipeline pipe(t);
  std::mt19937 rng(8);
  for (int i = 0; i < 15; ++i) {
    const BrushSettings s = randomBrush(rng, t.chart().sphereRadius(), t.grid().m());
    const core::GridPoint c = edittest::randomCentre(rng, t.grid().m());
    const std::vector<float> before(t.heights().begin(), t.heights().end());
    pipe.apply(GaussianBrush(s), {chart->position(c.u, c.v, 0.0), 0.0});
    ASSERT_TRUE(edittest::equalsBruteForce(pipe.field(), s.radius, pipe.lastRegion())) << i;
    checkEdit(t, pipe, before, "generic edit " + std::to_string(i));
  }
}

TEST(EditPipeline, FastStrokeLeavesNoGap) {
  auto chart = testkit::earthChart(8);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 0.0f));
  edit::EditPipeline pipe(t);
  const double R = testkit::kEarthRadius;
  BrushSettings s;
  s.radius = 600e3;
  s.strength = 1000;
  GaussianBrush brush(s);
  // One jump of about 3,300 km (30 degrees of longitude at 10 degrees north), across the seam.
  const Eigen::Vector3d a = edittest::latLon(10, 165, R), b = edittest::latLon(10, -165, R);
  pipe.beginStroke(brush, {a, 0});
  const auto rep = pipe.moveTo({b, 0});
  pipe.endStroke();
  const double arc = R * std::atan2(a.cross(b).norm(), a.dot(b));
  EXPECT_EQ(rep.stamps, int(std::floor(arc / (0.25 * s.radius))));
  // Every vertex nearest to the path is well inside some stamp.
  double lowest = 1e9;
  for (int i = 0; i <= 200; ++i) {
    const Eigen::Vector3d p =
        R * edit::slerpUnit(a.normalized(), b.normalized(), i / 200.0 * (1 - 0.2 * s.radius / arc));
    const core::GridPoint c = edit::nearestVertex(t.chart(), p);
    lowest = std::min(lowest, double(t.height(c.u, c.v)));
  }
  EXPECT_GT(lowest, 0.3 * s.strength) << "a gap along the stroke";
  EXPECT_TRUE(edittest::consistentHeights(t));
  EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  EXPECT_EQ(pipe.journal().undoCount(), 1u) << "a stroke is one undo step";
}

TEST(EditPipeline, ATeleportStampsAtMostTheCapAndStillReachesItsEnd) {
  // A 1 cm brush whose tool jumps half way round the planet in one sample (a tracking glitch):
  // floor(arc / spacing) would be 8e9 stamps. The sample stamps kMaxStampsPerSample times at a
  // stretched spacing, the last stamp at the sample, for stamp and rate tools alike.
  auto chart = testkit::earthChart(6);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 0.0f));
  edit::EditPipeline pipe(t);
  const double R = testkit::kEarthRadius;
  const Eigen::Vector3d a = edittest::latLon(5, 10, R), b = edittest::latLon(-5, -170, R);
  for (bool rate : {false, true}) {
    BrushSettings s;
    s.radius = 0.01;
    s.strength = 1;
    s.rate = rate;
    GaussianBrush brush(s);
    pipe.beginStroke(brush, {a, 0.0});
    const auto rep = pipe.moveTo({b, 1.0});
    EXPECT_EQ(rep.stamps, edit::EditPipeline::kMaxStampsPerSample) << "rate " << rate;
    // The last stamp was at the sample: the next sample at the same place stamps nothing (stamp
    // tool) or once (rate tool).
    EXPECT_EQ(pipe.moveTo({b, 0.5}).stamps, rate ? 1 : 0) << "rate " << rate;
    pipe.endStroke();
  }
  EXPECT_TRUE(edittest::consistentHeights(t));
}

TEST(EditPipeline, RateToolHeldStillActsPerSecondNotPerSample) {
  auto chart = testkit::earthChart(6);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 0.0f));
  edit::EditPipeline pipe(t);
  const Eigen::Vector3d p = chart->position(20, 12, 0.0);
  BrushSettings s;
  s.radius = 700e3;
  s.rate = true;
  s.strength = 40;  // m/s
  GaussianBrush rate(s);
  const auto c = pipe.beginStroke(rate, {p, 0.0}).control;
  for (int frame = 0; frame < 8; ++frame) EXPECT_EQ(pipe.moveTo({p, 0.125}).stamps, 1);
  pipe.endStroke();
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 40.0f);  // 1 s at 40 m/s
  // Per-stamp brush held still: nothing beyond the first stamp.
  s.rate = false;
  s.strength = 10;
  GaussianBrush stamp(s);
  pipe.beginStroke(stamp, {p, 0.0});
  for (int frame = 0; frame < 8; ++frame) EXPECT_EQ(pipe.moveTo({p, 0.125}).stamps, 0);
  pipe.endStroke();
  EXPECT_FLOAT_EQ(t.height(c.u, c.v), 50.0f);
}

TEST(EditPipeline, BadInputThrowsAndLeavesTheTerrainUntouched) {
  auto t = testkit::bumpyTerrain(6, 2, 4000.0);
  edit::EditPipeline pipe(t);
  const std::vector<float> heights(t.heights().begin(), t.heights().end());
  const auto codes = t.bounds().errorCodes();
  const auto revision = t.revision();
  const Eigen::Vector3d good = t.chart().position(10, 10, 0.0);
  struct Case {
    BrushSettings s;
    Eigen::Vector3d p;
    double dt;
    std::string expect;
  };
  auto brush = [](auto f) {
    BrushSettings s;
    f(s);
    return s;
  };
  const std::vector<Case> cases = {
      {brush([](BrushSettings& s) { s.radius = 0; }), good, 0, "r_d = 0"},
      {brush([](BrushSettings& s) { s.radius = -3e5; }), good, 0, "r_d = -300000"},
      {brush([](BrushSettings& s) { s.radius = NAN; }), good, 0, "r_d = nan"},
      {brush([](BrushSettings& s) { s.radius = INFINITY; }), good, 0, "r_d = inf"},
      {brush([](BrushSettings& s) { s.sigma = 0; }), good, 0, "sigma = 0"},
      {brush([](BrushSettings& s) { s.sigma = -1; }), good, 0, "sigma = -1"},
      {BrushSettings{}, Eigen::Vector3d::Zero(), 0, "centre"},
      {BrushSettings{}, Eigen::Vector3d(NAN, 0, 0), 0, "nan"},
      {BrushSettings{}, Eigen::Vector3d(0, -INFINITY, 0), 0, "-inf"},
      {BrushSettings{}, good, NAN, "dt = nan"},
      {BrushSettings{}, good, -1, "dt = -1"},
  };
  for (const Case& c : cases) {
    const GaussianBrush b(c.s);
    for (int way = 0; way < 2; ++way) {
      try {
        if (way == 0) {
          pipe.apply(b, {c.p, c.dt});
        } else {
          pipe.beginStroke(b, {c.p, c.dt});
        }
        FAIL() << "accepted: expected an error naming " << c.expect;
      } catch (const core::InputError& e) {
        EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
      }
      EXPECT_FALSE(pipe.inStroke());
    }
  }
  // A bad sample in the middle of a stroke: the stroke so far stays, the sample changes nothing.
  const GaussianBrush defaultBrush;
  pipe.beginStroke(defaultBrush, {good, 0});
  const std::vector<float> mid(t.heights().begin(), t.heights().end());
  EXPECT_THROW(pipe.moveTo({Eigen::Vector3d::Zero(), 0}), core::InputError);
  EXPECT_THROW(pipe.apply(GaussianBrush{}, {good, 0}), core::InputError);
  EXPECT_TRUE(edittest::sameBits(t.heights(), mid));
  pipe.endStroke();
  pipe.undo();
  EXPECT_TRUE(edittest::sameBits(t.heights(), heights));
  EXPECT_EQ(t.bounds().errorCodes(), codes);
  EXPECT_THROW(pipe.endStroke(), core::InputError);
  EXPECT_THROW(pipe.moveTo({good, 0}), core::InputError);
  (void)revision;
}

TEST(EditPipeline, NothingChangesOnRejectedInput) {
  auto t = testkit::bumpyTerrain(5, 2, 4000.0);
  edit::EditPipeline pipe(t);
  const auto revision = t.revision();
  const std::vector<float> heights(t.heights().begin(), t.heights().end());
  BrushSettings s;
  s.sigma = -1;
  EXPECT_THROW(pipe.apply(GaussianBrush(s), {t.chart().position(3, 3, 0.0), 0}), core::InputError);
  EXPECT_THROW(pipe.apply(GaussianBrush{}, {Eigen::Vector3d::Zero(), 0}), core::InputError);
  EXPECT_EQ(t.revision(), revision);
  EXPECT_TRUE(edittest::sameBits(t.heights(), heights));
  EXPECT_EQ(pipe.journal().undoCount(), 0u);
}

// The report's step times are measurements: `bench deform` prints them; a test asserts counts.
TEST(EditPipeline, ReportCountsTheRegionOfAPolarCap) {
  auto t = testkit::bumpyTerrain(8, 4, 3000.0);
  edit::EditPipeline pipe(t);
  const int m = t.grid().m();
  BrushSettings s;
  s.radius = 600e3;
  const auto rep =
      pipe.apply(GaussianBrush(s), {t.chart().position(0, 0, 0.0), 0});  // the south pole
  EXPECT_EQ(rep.control, (core::GridPoint{0, 0}));
  EXPECT_EQ(rep.modifiedVertices, edit::bruteForceRegion(pipe.field(), s.radius));
  EXPECT_EQ(rep.modifiedVertices % std::size_t(m + 1), 0u) << "a polar cap is whole rows";
  EXPECT_TRUE(rep.dirty.coversAllColumns(t.grid()));
  EXPECT_EQ(rep.dirty.vBegin, 0);
  EXPECT_GT(rep.boundsVertices, rep.modifiedPoints / 2);
  EXPECT_TRUE(edittest::consistentHeights(t));
}
