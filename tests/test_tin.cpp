// The TIN mesher (src/tin): the error it promises, measured on every sample by an independent
// locator; its angles; control maps; the planet's welded, closed surface.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/input_error.hpp"
#include "test_terrains.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::tin {
namespace {

// Random relief: smooth hills, a cliff (a step no plane fits) and sample noise.
std::vector<float> randomRelief(int w, int h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  struct Hill {
    double x, y, r, a;
  };
  std::vector<Hill> hills;
  for (int k = 0; k < 12; ++k)
    hills.push_back({uni(rng) * w, uni(rng) * h, 2 + uni(rng) * w / 3.0, 40 * (uni(rng) - 0.4)});
  const double cliffX = w * (0.3 + 0.4 * uni(rng));
  std::vector<float> out(std::size_t(w) * std::size_t(h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      double z = i > cliffX ? 15.0 : 0.0;
      for (const Hill& c : hills)
        z += c.a * std::exp(-((i - c.x) * (i - c.x) + (j - c.y) * (j - c.y)) / (c.r * c.r));
      out[std::size_t(j) * std::size_t(w) + std::size_t(i)] = float(z + 0.3 * (uni(rng) - 0.5));
    }
  return out;
}

SampleField flatField(int w, int h, const std::vector<float>& heights, double tolerance) {
  SampleField f;
  f.width = w;
  f.height = h;
  f.heights = heights;
  f.uniformTolerance = tolerance;
  return f;
}

void expectFlatTinSound(const SampleField& field, const Tin& tin) {
  const TinErrorCheck check = measureTinError(field, tin);
  EXPECT_EQ(check.uncovered, 0u);
  EXPECT_EQ(check.samples, std::size_t(field.width) * std::size_t(field.height));
  EXPECT_LE(check.maxRatio, 1.0 + 1e-9) << "worst sample " << check.worstSample;
  const MeshTopology top = meshTopology(tin.xy.size(), tin.triangles);
  EXPECT_EQ(top.nonManifoldEdges, 0u);
  EXPECT_EQ(top.degenerate, 0u);
  EXPECT_EQ(top.euler(), 1) << "a TIN over a rectangle is a disk";
  for (const double h : tin.h) EXPECT_TRUE(std::isfinite(h));
}

TEST(TinMesher, GreedyHoldsTheErrorOnEverySampleOfRandomReliefs) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    const int w = 9 + int(rng() % 70), h = 9 + int(rng() % 70);
    const auto heights = randomRelief(w, h, std::uint32_t(rng()));
    const double tol = 0.05 + 3.0 * double(rng() % 1000) / 1000.0;
    const SampleField field = flatField(w, h, heights, tol);
    TinReport rep;
    const Tin tin = buildTin(field, {}, &rep);
    SCOPED_TRACE(testing::Message() << w << "x" << h << " tolerance " << tol);
    expectFlatTinSound(field, tin);
    EXPECT_EQ(rep.vertices, tin.xy.size());
    EXPECT_EQ(rep.steinerVertices, 0u);
    EXPECT_LT(tin.xy.size(), std::size_t(w) * std::size_t(h)) << "greedy keeps fewer than all";
  }
}

TEST(TinMesher, RemovingRedundantVerticesKeepsTheErrorAndNeverAddsTriangles) {
  // Integer heights (as real DEMs store them) make cocircular and tied cases common: the
  // removal's own hole triangulation must agree with CGAL's or notice that it may not.
  std::mt19937 rng(19);
  std::size_t removedAll = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const int w = 17 + int(rng() % 80), h = 17 + int(rng() % 80);
    auto heights = randomRelief(w, h, std::uint32_t(rng()));
    if (trial % 2 == 1)
      for (float& z : heights) z = std::round(4 * z);
    const double tol = 0.25 + 4.0 * double(rng() % 1000) / 1000.0;
    const SampleField field = flatField(w, h, heights, tol);
    TinReport plainRep, rep;
    const Tin plain = buildTin(field, {.removeRedundant = false}, &plainRep);
    const Tin tin = buildTin(field, {}, &rep);
    SCOPED_TRACE(testing::Message() << w << "x" << h << " tolerance " << tol);
    expectFlatTinSound(field, tin);
    EXPECT_EQ(plainRep.removedVertices, 0u);
    EXPECT_LE(tin.triangles.size(), plain.triangles.size());
    EXPECT_EQ(rep.vertices, tin.xy.size());
    removedAll += rep.removedVertices;
  }
  EXPECT_GT(removedAll, 0u) << "the reliefs have vertices the error does not need";
}

TEST(TinMesher, APlaneNeedsOnlyItsCorners) {
  const int w = 40, h = 23;
  std::vector<float> heights(std::size_t(w) * std::size_t(h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) heights[std::size_t(j * w + i)] = float(0.5 * i - 0.25 * j + 3);
  const Tin tin = buildTin(flatField(w, h, heights, 1e-3), {});
  EXPECT_EQ(tin.xy.size(), 4u);
  EXPECT_EQ(tin.triangles.size(), 2u);
}

TEST(TinMesher, FinerToleranceNeverNeedsFewerVertices) {
  const int w = 65, h = 48;
  const auto heights = randomRelief(w, h, 3);
  std::size_t last = 0;
  for (const double tol : {4.0, 2.0, 1.0, 0.5, 0.25}) {
    const Tin tin = buildTin(flatField(w, h, heights, tol), {});
    EXPECT_GE(tin.xy.size(), last) << "tolerance " << tol;
    last = tin.xy.size();
  }
}

TEST(TinMesher, QualityModeReachesTheProvenAngleAndKeepsTheError) {
  const int w = 57, h = 41;
  const auto heights = randomRelief(w, h, 11);
  const SampleField field = flatField(w, h, heights, 0.5);
  TinReport greedy, quality;
  const Tin fewest = buildTin(field, {}, &greedy);
  const Tin tin = buildTin(field, {.minAngleDeg = 20.0}, &quality);
  expectFlatTinSound(field, tin);
  EXPECT_TRUE(quality.angleMet);
  EXPECT_FALSE(quality.budgetExhausted);
  EXPECT_GE(quality.smallestAngleDeg, 20.0);
  EXPECT_LT(greedy.smallestAngleDeg, 20.0) << "the greedy TIN has slivers the refinement removed";
  EXPECT_GT(tin.triangles.size(), fewest.triangles.size());
}

TEST(TinMesher, AboveTheProvenAngleTheBudgetEndsItAndTheErrorStillHolds) {
  const int w = 50, h = 50;
  const auto heights = randomRelief(w, h, 5);
  const SampleField field = flatField(w, h, heights, 0.4);
  TinReport rep;
  const Tin tin = buildTin(field, {.minAngleDeg = 33.0, .steinerBudget = 50}, &rep);
  expectFlatTinSound(field, tin);
  EXPECT_TRUE(rep.budgetExhausted);
  EXPECT_EQ(rep.angleMet, rep.smallestAngleDeg + 1e-6 >= 33.0);
  TinReport generous;
  buildTin(field, {.minAngleDeg = 30.0}, &generous);
  EXPECT_TRUE(generous.angleMet) << "30 degrees is usually reached: " << generous.smallestAngleDeg;
}

TEST(TinMesher, AControlMapTightensTheErrorWhereItIsWhite) {
  const int w = 80, h = 60;
  const auto heights = randomRelief(w, h, 21);
  std::vector<float> tolerance(heights.size(), 2.0f);
  for (int j = 20; j < 40; ++j)
    for (int i = 10; i < 30; ++i) tolerance[std::size_t(j * w + i)] = 0.1f;
  SampleField field = flatField(w, h, heights, 2.0);
  field.perSampleTolerance = tolerance;
  const Tin tin = buildTin(field, {});
  expectFlatTinSound(field, tin);
  const Tin everywhereFine = buildTin(flatField(w, h, heights, 0.1), {});
  const Tin everywhereCoarse = buildTin(flatField(w, h, heights, 2.0), {});
  EXPECT_LT(tin.triangles.size(), everywhereFine.triangles.size());
  EXPECT_GT(tin.triangles.size(), everywhereCoarse.triangles.size());
}

TEST(TinMesher, APlanetTinIsClosedAndWithinItsError) {
  for (const double tol : {4000.0, 600.0}) {
    const terrain::Terrain t = testkit::bumpyTerrain(6, 4, 20000.0);
    SampleField field;
    field.width = field.height = t.grid().side();
    field.heights = t.heights();
    field.metric = ErrorMetric::kChart3d;
    field.chart = &t.chart();
    field.uniformTolerance = tol;
    TinReport rep;
    const Tin tin = buildTin(field, {}, &rep);
    SCOPED_TRACE(testing::Message() << "tolerance " << tol << ", " << tin.xy.size() << " vertices");
    const TinErrorCheck check = measureTinError(field, tin);
    EXPECT_EQ(check.uncovered, 0u);
    EXPECT_LE(check.maxRatio, 1.0 + 1e-9);
    const WeldedMesh welded = weldTin(field, tin);
    const MeshTopology top = meshTopology(welded.vertices, welded.triangles);
    EXPECT_EQ(top.borderEdges, 0u) << "seam and poles closed";
    EXPECT_EQ(top.nonManifoldEdges, 0u);
    EXPECT_EQ(top.degenerate, 0u);
    EXPECT_EQ(top.euler(), 2) << "a sphere";
  }
}

TEST(TinMesher, APlanetQualityTinKeepsItsSeamClosed) {
  const terrain::Terrain t = testkit::bumpyTerrain(5, 6, 20000.0);
  SampleField field;
  field.width = field.height = t.grid().side();
  field.heights = t.heights();
  field.metric = ErrorMetric::kChart3d;
  field.chart = &t.chart();
  field.uniformTolerance = 3000.0;
  TinReport rep;
  const Tin tin = buildTin(field, {.minAngleDeg = 20.0}, &rep);
  EXPECT_GT(rep.steinerVertices, 0u);
  const TinErrorCheck check = measureTinError(field, tin);
  EXPECT_EQ(check.uncovered, 0u);
  EXPECT_LE(check.maxRatio, 1.0 + 1e-9);
  const WeldedMesh welded = weldTin(field, tin);
  const MeshTopology top = meshTopology(welded.vertices, welded.triangles);
  EXPECT_EQ(top.borderEdges, 0u);
  EXPECT_EQ(top.nonManifoldEdges, 0u);
  EXPECT_EQ(top.degenerate, 0u);
  EXPECT_EQ(top.euler(), 2);
}

TEST(TinMesher, RefusesWhatItCannotDo) {
  const int w = 10, h = 10;
  const auto heights = randomRelief(w, h, 1);
  EXPECT_THROW(buildTin(flatField(w, h, heights, 0.0), {}), core::InputError);
  EXPECT_THROW(buildTin(flatField(w, h, heights, -1.0), {}), core::InputError);
  EXPECT_THROW(buildTin(flatField(w, h, heights, NAN), {}), core::InputError);
  EXPECT_THROW(buildTin(flatField(w, h, heights, 1.0), {.minAngleDeg = 40.0}), core::InputError);
  EXPECT_THROW(buildTin(flatField(w, h, heights, 1.0), {.minAngleDeg = -1.0}), core::InputError);
  EXPECT_THROW(buildTin(flatField(1, 100, heights, 1.0), {}), core::InputError);
  std::vector<float> badTolerance(heights.size(), 1.0f);
  badTolerance[7] = 0.0f;
  SampleField field = flatField(w, h, heights, 1.0);
  field.perSampleTolerance = badTolerance;
  EXPECT_THROW(buildTin(field, {}), core::InputError);
}

}  // namespace
}  // namespace ps::tin
