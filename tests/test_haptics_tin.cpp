// The haptic path over the sand TIN's region (issue 27): the snapshot carries the region TIN's
// triangles near the tool, and the probe measures depth under them inside the region (checked
// against a brute-force search of every TIN triangle) and under the grid's bilinear surface
// outside it (bit for bit what the grid-only snapshot gives); an imprint narrower than a grid
// cell is felt at its TIN depth; the haptic thread's work allocates nothing; force logs repeat.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <new>
#include <numbers>
#include <random>
#include <sstream>

#include "edit/control_vertex.hpp"
#include "edit/edit_pipeline.hpp"
#include "haptics/force_path.hpp"
#include "haptics/haptic_core.hpp"
#include "haptics/terrain_patch.hpp"
#include "haptics/triple_buffer.hpp"
#include "sand/stroke_tin.hpp"
#include "sand/tin_sand_tool.hpp"
#include "small_planet.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

// Counts the allocations of the thread that asks (the haptic work under test), so that the rule
// "nothing on the haptic thread allocates" is checked rather than read off the code. The
// replacement is global to the test binary, so the sanitizers' build leaves it out: there their
// own operator new checks every test for mismatched new and delete.
namespace {
thread_local bool tCountAllocations = false;
std::atomic<long> gAllocations{0};
}  // namespace

#if defined(__SANITIZE_ADDRESS__)  // g++
#define PS_TEST_ASAN 1
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
#define PS_TEST_ASAN 1
#endif
#endif
#if defined(PS_TEST_ASAN)
constexpr bool kAllocationsCounted = false;
#else
constexpr bool kAllocationsCounted = true;
// The replaced operator delete frees what the replaced operator new got from malloc; g++ sees
// only the standard names pairing new with free where it inlines them.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  if (tCountAllocations) gAllocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#endif

using namespace ps;

namespace {

using testkit::aboveSmallPlanet;
using testkit::kSmallPlanetRadius;
using testkit::SmallPlanet;

// A short stroke of the TIN sand tool (1,200 m stamps pressed 300 m) from 10 N 30 E to 32 E
// (690 m): the region TIN it leaves (a quarter of this 20 km planet's radius: 5 km, 14 degrees)
// and its patch as the view draws it.
struct Stroked {
  SmallPlanet p;
  sand::TinSandTool tool{p.chart, [] {
                           sand::TinSandToolSettings s;
                           s.radius = 1200.0;
                           return s;
                         }()};
  std::shared_ptr<const terrain::MeshPatch> patch;
  Stroked() {
    const double r = tool.settings().radius;
    p.pipe.beginStroke(tool, {aboveSmallPlanet(10.0, 30.0, r - 300.0), 0.0});
    for (double d = 0.2; d <= 2.0 + 1e-9; d += 0.2)
      p.pipe.moveTo({aboveSmallPlanet(10.0, 30.0 + d, r - 300.0), 0.0});
    p.pipe.endStroke();
    if (tool.strokeTin() && tool.strokeTin()->holds(p.t.heights()))
      patch = std::make_shared<const terrain::MeshPatch>(tool.strokeTin()->patch());
  }
};

// Brute force: the height of the patch's surface at (x, y) of its plane, over every triangle.
std::optional<double> bruteHeight(const terrain::MeshPatch& m, const Eigen::Vector2d& q) {
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const Eigen::Vector2d a = m.xy[m.indices[t]], b = m.xy[m.indices[t + 1]],
                          c = m.xy[m.indices[t + 2]];
    auto cross = [](const Eigen::Vector2d& x, const Eigen::Vector2d& y) {
      return x.x() * y.y() - x.y() * y.x();
    };
    const double d = cross(b - a, c - a);
    if (d == 0) continue;
    const double la = cross(b - q, c - q) / d, lb = cross(c - q, a - q) / d, lc = 1 - la - lb;
    if (la >= -1e-12 && lb >= -1e-12 && lc >= -1e-12)
      return la * m.heights[m.indices[t]] + lb * m.heights[m.indices[t + 1]] +
             lc * m.heights[m.indices[t + 2]];
  }
  return std::nullopt;
}

Eigen::Vector2d planeXY(const terrain::MeshPatch& m, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p.normalized();
  return {m.plane->radius * d.dot(m.plane->east), m.plane->radius * d.dot(m.plane->north)};
}

TEST(HapticsTin, DepthIsTheTinsInsideTheRegionAndTheGridsBitForBitOutside) {
  Stroked s;
  ASSERT_TRUE(s.patch && s.patch->plane) << "the stroke left a region TIN the grid holds";
  EXPECT_DOUBLE_EQ(s.patch->plane->radius, kSmallPlanetRadius);
  const Eigen::Vector3d centre = aboveSmallPlanet(10.0, 31.0, 0.0);
  haptics::TerrainPatch withTin, gridOnly;
  ASSERT_TRUE(withTin.capture(s.p.t, centre, 40, s.patch.get()));
  ASSERT_TRUE(gridOnly.capture(s.p.t, centre, 40));
  EXPECT_EQ(gridOnly.surfaceTriangles(), 0u);
  EXPECT_EQ(withTin.surfaceTriangles(), s.patch->indices.size() / 3)
      << "a 5 km region inside a 20 km reach: every triangle";
  std::mt19937 rng(27);
  // The region and as far again around it.
  std::uniform_real_distribution<double> lat(-10.0, 30.0), lon(9.0, 53.0), h(-400.0, 400.0);
  int inside = 0, outside = 0, differ = 0;
  double worst = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector3d p = aboveSmallPlanet(lat(rng), lon(rng), h(rng));
    const auto probe = withTin.probe(p);
    const auto grid = gridOnly.probe(p);
    ASSERT_TRUE(probe && grid);
    if (const auto th = bruteHeight(*s.patch, planeXY(*s.patch, p))) {
      ++inside;
      const double expected = kSmallPlanetRadius + *th - p.norm();
      worst = std::max(worst, std::abs(probe->depth - expected));
      ASSERT_NEAR(probe->depth, expected, 1e-7) << "at " << p.transpose();
      ASSERT_LT((probe->up - p.normalized()).norm(), 1e-12) << "radial";
      if (std::abs(probe->depth - grid->depth) > 0.5) ++differ;
    } else {
      ++outside;
      ASSERT_EQ(probe->depth, grid->depth) << "outside the region: the grid's, bit for bit";
      ASSERT_EQ(probe->surface, grid->surface);
      ASSERT_EQ(probe->up, grid->up);
    }
  }
  std::cout << "TIN " << s.patch->positions.size() << " vertices, " << s.patch->indices.size() / 3
            << " triangles; " << inside << " points inside (largest difference from brute force "
            << worst << " m; " << differ << " more than 0.5 m from the grid's depth), " << outside
            << " outside\n";
  EXPECT_GT(inside, 4000);
  EXPECT_GT(outside, 1000);

  // Across the region's border the two surfaces agree as far as the TIN's heights and the
  // grid's bilinear surface agree there: a walk out along the parallel steps by no more.
  const Eigen::Vector3d start = aboveSmallPlanet(10.0, 31.0, -20.0);
  double lastDepth = withTin.probe(start)->depth, largestStep = 0;
  bool wasInside = true;
  int crossings = 0;
  for (double d = 0.05; d <= 25.0; d += 0.05) {
    const Eigen::Vector3d p = aboveSmallPlanet(10.0, 31.0 + d, -20.0);
    const bool in = bool(bruteHeight(*s.patch, planeXY(*s.patch, p)));
    const double depth = withTin.probe(p)->depth;
    if (in != wasInside) {
      ++crossings;
      largestStep = std::max(largestStep, std::abs(depth - lastDepth));
    }
    wasInside = in;
    lastDepth = depth;
  }
  std::cout << "border crossed " << crossings << " time(s), depth step " << largestStep
            << " m (tolerance " << 1e-3 * 1200.0 << " m)\n";
  EXPECT_EQ(crossings, 1);
  EXPECT_LT(largestStep, 5.0) << "the relief's change over a 17 m step and the TIN's 1.2 m "
                                 "tolerance";
}

TEST(HapticsTin, OnAFlatGridTheDepthIsTheTinsHeightMinusZInsideAndTheGridsOutside) {
  auto chart = sandtest::flatChart(7);  // 129^2, 1 m cells
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 20.0f));
  edit::EditPipeline pipe(t);
  sand::TinSandToolSettings ts;
  ts.radius = 8.0;
  sand::TinSandTool tool(chart, ts);
  pipe.apply(tool, {{64.0, 64.0, 20.0 - 4.0 + 8.0}, 0.0});
  ASSERT_TRUE(tool.strokeTin() && tool.strokeTin()->holds(t.heights()));
  const terrain::MeshPatch patch = tool.strokeTin()->patch();
  ASSERT_TRUE(patch.plane);
  EXPECT_EQ(patch.plane->radius, 0.0);
  haptics::TerrainPatch withTin, gridOnly;
  ASSERT_TRUE(withTin.capture(t, {64.0, 64.0, 20.0}, 60, &patch));
  ASSERT_TRUE(gridOnly.capture(t, {64.0, 64.0, 20.0}, 60));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(4.0, 124.0), z(10.0, 25.0);
  int inside = 0, outside = 0;
  for (int k = 0; k < 5000; ++k) {
    const Eigen::Vector3d p(xy(rng), xy(rng), z(rng));
    const auto probe = withTin.probe(p);
    const auto grid = gridOnly.probe(p);
    ASSERT_TRUE(probe && grid);
    const Eigen::Vector3d q = p - patch.plane->origin;
    const Eigen::Vector2d at(q.dot(patch.plane->east), q.dot(patch.plane->north));
    if (const auto th = bruteHeight(patch, at)) {
      ++inside;
      ASSERT_NEAR(probe->depth, *th - q.dot(patch.plane->up), 1e-9);
    } else {
      ++outside;
      ASSERT_EQ(probe->depth, grid->depth);
      ASSERT_EQ(probe->surface, grid->surface);
    }
  }
  EXPECT_GT(inside, 200);
  EXPECT_GT(outside, 2000);
}

TEST(HapticsTin, AnImprintNarrowerThanAGridCellIsFeltAtItsTinDepth) {
  SmallPlanet p;
  sand::TinSandTool tool(p.chart, [] {
    sand::TinSandToolSettings s;
    s.radius = 1200.0;
    return s;
  }());
  p.pipe.apply(tool, {aboveSmallPlanet(10.0, 30.0, 900.0), 0.0});
  ASSERT_TRUE(tool.strokeTin());
  // A region of our own (the tool's is const), on the same footprint.
  const Eigen::Vector3d at = aboveSmallPlanet(10.0, 30.0, 0.0);
  sand::StrokeTin region(*p.chart, p.t.heights(), tool.strokeTin()->footprint(),
                         edit::nearestVertex(*p.chart, at), 1.2, sand::TinSandSettings{});
  // A press 0.3 cells wide in the middle of a cell: no grid vertex under it.
  const core::GridPoint g = edit::nearestVertex(*p.chart, at);
  const Eigen::Vector2d mid =
      region.frame().project(p.chart->positionAt(g.u + 0.5, g.v + 0.5, 0.0));
  const double cell = std::numbers::pi * kSmallPlanetRadius / p.chart->grid().m();
  const double before = region.sand().tin().heightAt(mid);
  const double bottom = before - 50.0;
  sand::TinStampTool disc = sand::TinStampTool::disc(0.3 * cell);
  disc.pushAside = false;
  region.sand().stamp(mid, bottom, disc);
  const auto patch = std::make_shared<const terrain::MeshPatch>(region.patch());
  ASSERT_NEAR(*bruteHeight(*patch, mid), bottom, 1e-9);

  haptics::TerrainPatch withTin, gridOnly;
  ASSERT_TRUE(withTin.capture(p.t, at, 10, patch.get()));
  ASSERT_TRUE(gridOnly.capture(p.t, at, 10));
  const Eigen::Vector3d dir =
      (mid.x() * region.frame().east + mid.y() * region.frame().north +
       std::sqrt(kSmallPlanetRadius * kSmallPlanetRadius - mid.squaredNorm()) * region.frame().up)
          .normalized();
  for (const double above_bottom : {-5.0, 10.0}) {
    const Eigen::Vector3d tip = dir * (kSmallPlanetRadius + bottom + above_bottom);
    const auto tin = withTin.probe(tip);
    const auto grid = gridOnly.probe(tip);
    ASSERT_TRUE(tin && grid);
    EXPECT_NEAR(tin->depth, -above_bottom, 1e-6) << "the imprint's floor";
    EXPECT_GT(grid->depth, 30.0) << "the grid's bilinear surface never saw the imprint";
    std::cout << "tip " << above_bottom << " m above the imprint's floor: depth " << tin->depth
              << " m under the TIN, " << grid->depth << " m under the grid\n";
  }
}

TEST(HapticsTin, TheHapticThreadsWorkAllocatesNothingOverTheTin) {
  if (!kAllocationsCounted)
    GTEST_SKIP() << "the sanitizers' build keeps their own operator new (the release build counts)";
  Stroked s;
  ASSERT_TRUE(s.patch);
  haptics::TripleBuffer<haptics::TerrainPatch> buffer;
  const Eigen::Vector3d centre = aboveSmallPlanet(10.0, 31.0, 0.0);
  ASSERT_TRUE(buffer.back().capture(s.p.t, centre, 40, s.patch.get()));
  buffer.publish();
  haptics::WorkspaceMap map;
  map.scale = 1e5;  // 1 cm of hand motion is 1 km on this planet
  haptics::HapticCore core(haptics::HapticSettings{}, map);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> wobble(-0.2, 0.2);
  int touching = 0, onTin = 0;
  gAllocations = 0;
  tCountAllocations = true;
  for (int k = 0; k < 5000; ++k) {
    buffer.update();
    const haptics::TerrainPatch& patch = buffer.front();
    // In and out of the sand along the stroke, across the region's border.
    const double lonDeg = 30.5 + 20.0 * k / 5000.0, depth = 150.0 + 250.0 * std::sin(k * 0.01);
    const Eigen::Vector3d tip = aboveSmallPlanet(10.0 + wobble(rng) * 0.01, lonDeg, -depth);
    const auto rec = core.tick(k * 1e-3, true, map.toDevice(tip), &patch);
    touching += rec.touching;
    const auto probe = patch.probe(tip);
    onTin += probe && patch.surfaceHeightAt(planeXY(*s.patch, tip)).has_value();
  }
  tCountAllocations = false;
  EXPECT_EQ(gAllocations.load(), 0) << "ticks and probes over the TIN allocate nothing";
  EXPECT_GT(touching, 1000);
  EXPECT_GT(onTin, 1000);
  // The editor's second capture into the same slot reuses its buffers.
  haptics::TerrainPatch slot;
  ASSERT_TRUE(slot.capture(s.p.t, centre, 40, s.patch.get()));
  gAllocations = 0;
  tCountAllocations = true;
  const bool again = slot.capture(s.p.t, aboveSmallPlanet(10.0, 31.01, 0.0), 40, s.patch.get());
  tCountAllocations = false;
  EXPECT_TRUE(again);
  EXPECT_EQ(gAllocations.load(), 0) << "a capture of the same size allocates nothing";
}

TEST(HapticsTin, ForcePathOverTheTinLogsTheSameTwice) {
  Stroked s;
  ASSERT_TRUE(s.patch);
  auto run = [&] {
    haptics::ForcePathConfig cfg;
    cfg.map.scale = 1e5;
    cfg.press.displacement.radius = 1200.0;
    haptics::ForcePath path(s.p.t, nullptr, cfg);
    std::ostringstream log;
    path.setLog(&log);
    path.setSurface(s.patch);
    int touching = 0;
    for (int f = 0; f < 90; ++f) {
      const double d = f / 90.0;
      const double h = 100.0 - 500.0 * std::sin(std::numbers::pi * d);
      const auto ff = path.onFrame(aboveSmallPlanet(10.0, 30.5 + d, h), f / 30.0);
      touching += ff.touchingTicks;
    }
    path.setLog(nullptr);
    EXPECT_GT(touching, 500);
    return log.str();
  };
  const std::string a = run(), b = run();
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
}

}  // namespace
