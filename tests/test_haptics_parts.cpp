// The haptic path's parts: terrain snapshots (patch), wait-free hand-over buffers, devices, the
// force log.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <thread>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "haptics/device.hpp"
#include "haptics/force_log.hpp"
#include "haptics/haptic_core.hpp"
#include "haptics/spsc_queue.hpp"
#include "haptics/terrain_patch.hpp"
#include "haptics/triple_buffer.hpp"
#include "terrain/terrain.hpp"
#include "test_haptics_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using namespace ps::haptics;

TEST(HapticsPatch, BilinearHeightsMatchTheTerrainAtGridPoints) {
  const terrain::Terrain t = haptictest::reliefPlanet(8);
  const int m = t.grid().m();
  TerrainPatch p;
  ASSERT_TRUE(p.capture(t, haptictest::latLon(20, 30, haptictest::kR), 10));
  EXPECT_EQ(p.revision(), t.revision());
  int checked = 0;
  for (int v = p.v0(); v < p.v0() + p.rows(); ++v) {
    for (int c = 0; c < p.cols(); ++c) {
      const int u = p.u0() + c;
      ASSERT_TRUE(u >= 0 && u <= m);
      ASSERT_EQ(*p.heightAt(u, v), double(t.height(u, v)));
      ++checked;
    }
  }
  EXPECT_GT(checked, 400);
  EXPECT_FALSE(p.heightAt(p.u0() - 1.5, p.v0() + 2));  // outside
  EXPECT_FALSE(p.heightAt(p.u0() + 2, p.v0() + p.rows() + 0.5));
  EXPECT_FALSE(p.heightAt(haptictest::kNaN, 3));
}

TEST(HapticsPatch, ProbeIsRadialDepthAndContinuousAcrossTheSeamAndPoles) {
  const terrain::Terrain t = haptictest::reliefPlanet(8);
  // Depth on a sphere: R + h(foot point) - |p|.
  for (double lon : {-180.0, -179.9, 179.9, 0.0, 45.0}) {
    for (double lat : {-89.95, -60.0, 0.0, 30.0, 89.99}) {
      const Eigen::Vector3d dir = haptictest::latLon(lat, lon, 1.0);
      TerrainPatch p;
      ASSERT_TRUE(p.capture(t, dir * haptictest::kR, 16));
      const auto uv = t.chart().inverse(dir);
      // Bilinear height from the full terrain at the foot point.
      const double u = (*uv)(0), v = (*uv)(1);
      const int iu = std::min(int(u), t.grid().m() - 1), iv = std::min(int(v), t.grid().m() - 1);
      const double a = u - iu, b = v - iv;
      const double h = (1 - b) * ((1 - a) * t.height(iu, iv) + a * t.height(iu + 1, iv)) +
                       b * ((1 - a) * t.height(iu, iv + 1) + a * t.height(iu + 1, iv + 1));
      for (double alt : {-2000.0, 0.0, 4000.0}) {
        const auto s = p.probe(dir * (haptictest::kR + alt));
        ASSERT_TRUE(s) << lat << " " << lon;
        EXPECT_NEAR(s->depth, h - alt, 1e-6 * haptictest::kR * 1e-3)
            << lat << " " << lon << " " << alt;
        EXPECT_NEAR((s->up - dir).norm(), 0.0, 1e-9);
      }
    }
  }
  // Walking across the seam at 1 km steps: depth changes by at most (1 + slope) x step.
  TerrainPatch p;
  ASSERT_TRUE(p.capture(t, haptictest::latLon(10, 180, haptictest::kR), 32));
  double prev = p.probe(haptictest::latLon(10, 179.5, haptictest::kR))->depth;
  const double stepDeg = 1000.0 / haptictest::kR * 180 / std::numbers::pi;
  for (double lon = 179.5 + stepDeg; lon < 180.5; lon += stepDeg) {
    const auto s = p.probe(haptictest::latLon(10, lon, haptictest::kR));
    ASSERT_TRUE(s) << lon;
    // slope of the relief <= 3000 * 3 / R * 2 (lon derivative, bilinear) < 0.01
    EXPECT_LE(std::abs(s->depth - prev), 1000.0 * 0.01 + 1e-3) << lon;
    prev = s->depth;
  }
  // Next to a pole the patch holds whole rows.
  ASSERT_TRUE(p.capture(t, haptictest::latLon(89.5, 10, haptictest::kR), 4));
  EXPECT_EQ(p.cols(), t.grid().side());
  for (double lon = -180; lon <= 180; lon += 7)
    EXPECT_TRUE(p.probe(haptictest::latLon(89.6, lon, haptictest::kR)));
}

TEST(HapticsPatch, OctahedralPatchesReachAcrossTheFolds) {
  // A tool by a fold, at the south pole (the four corners) and at a side's midpoint: foot points
  // on the other side of the fold (the inverse puts them elsewhere in the square) are in the
  // patch, at the full terrain's bilinear depth.
  const terrain::Terrain t = testkit::bumpyOctahedralTerrain(7, 3, 2000.0);
  const core::Chart& chart = t.chart();
  const int m = t.grid().m();
  auto fullDepth = [&](const Eigen::Vector3d& p) {
    const auto uv = chart.inverse(p);
    const double u = (*uv)(0), v = (*uv)(1);
    const int iu = std::min(int(u), m - 1), iv = std::min(int(v), m - 1);
    const double a = u - iu, b = v - iv;
    const double h = (1 - b) * ((1 - a) * t.height(iu, iv) + a * t.height(iu + 1, iv)) +
                     b * ((1 - a) * t.height(iu, iv + 1) + a * t.height(iu + 1, iv + 1));
    return haptictest::kR + h - p.norm();
  };
  for (const core::GridPoint at : {core::GridPoint{0, m / 4}, core::GridPoint{0, 0},
                                   core::GridPoint{m / 2, 0}, core::GridPoint{m / 3, m}}) {
    const Eigen::Vector3d c = chart.up(at.u, at.v);
    TerrainPatch p;
    ASSERT_TRUE(p.capture(t, c * haptictest::kR, 6));
    EXPECT_GT(p.images(), 0);
    // A ring of points about the tool, 3 cells away: half of it lies across the fold.
    const Eigen::Vector3d e1 = c.unitOrthogonal(), e2 = c.cross(e1);
    const double ang = 3.0 * 2.0 * std::numbers::pi / (4.0 * m);
    for (int k = 0; k < 16; ++k) {
      const double phi = 2 * std::numbers::pi * k / 16;
      const Eigen::Vector3d d =
          (std::cos(ang) * c + std::sin(ang) * (std::cos(phi) * e1 + std::sin(phi) * e2))
              .normalized();
      const auto s = p.probe(d * (haptictest::kR + 100.0));
      ASSERT_TRUE(s) << at.u << "," << at.v << " k " << k;
      EXPECT_NEAR(s->depth, fullDepth(d * (haptictest::kR + 100.0)), 1e-6 * haptictest::kR * 1e-3)
          << at.u << "," << at.v << " k " << k;
    }
  }
}

TEST(HapticsPatch, FlatChartDepthIsHeightMinusZ) {
  auto chart = sandtest::flatChart(6, 0.01, 0.01);  // 65^2, 1 cm cells
  auto h = sandtest::heightsFrom(*chart, [](int u, int v) { return 0.001 * (u + 2 * v); });
  const terrain::Terrain t(chart, std::move(h));
  TerrainPatch p;
  ASSERT_TRUE(p.capture(t, {0.3, 0.3, 0}, 8));
  const auto s = p.probe({0.305, 0.2975, 0.05});
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->depth, 0.001 * (30.5 + 2 * 29.75) - 0.05, 1e-9);
  EXPECT_FALSE(p.probe({0.6, 0.3, 0}));  // outside the snapshot
}

TEST(HapticsBuffers, TripleBufferHandsOverTheNewestValueWithoutWaiting) {
  TripleBuffer<int> b;
  EXPECT_FALSE(b.update());
  b.back() = 1;
  b.publish();
  b.back() = 2;
  b.publish();  // overwrites 1 before the reader saw it
  EXPECT_TRUE(b.update());
  EXPECT_EQ(b.front(), 2);
  EXPECT_FALSE(b.update());
  EXPECT_EQ(b.front(), 2);  // stays
  // Two threads: the reader only ever sees values the writer published, in increasing order.
  TripleBuffer<std::array<int, 64>> big;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (int i = 1; i <= 200000; ++i) {
      big.back().fill(i);
      big.publish();
    }
    done = true;
  });
  // Violations are counted, not asserted, inside the loop: an ASSERT returning here would leave
  // the writer thread joinable and terminate the test binary instead of failing the test.
  int last = 0, seen = 0, torn = 0, notNewer = 0;
  for (;;) {
    const bool finished = done.load();
    if (big.update()) {
      const auto& a = big.front();
      for (int x : a) torn += x != a[0] ? 1 : 0;
      notNewer += a[0] <= last ? 1 : 0;
      last = a[0];
      ++seen;
    } else if (finished) {
      break;
    }
  }
  writer.join();
  EXPECT_EQ(torn, 0) << "a reader saw a half-written value";
  EXPECT_EQ(notNewer, 0) << "a reader saw a value no newer than the previous one";
  EXPECT_EQ(last, 200000);  // the newest value always arrives
  EXPECT_GT(seen, 0);
}

TEST(HapticsBuffers, SpscQueueKeepsOrderAndCountsDrops) {
  SpscQueue<int> q(8);
  EXPECT_EQ(q.capacity(), 8u);
  for (int i = 0; i < 10; ++i) q.push(i);
  EXPECT_EQ(q.dropped(), 2u);
  std::vector<int> out;
  EXPECT_EQ(q.drain(out), 8u);
  EXPECT_EQ(out, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  SpscQueue<long> big(1024);
  std::thread producer([&] {
    for (long i = 0; i < 300000; ++i) {
      while (!big.push(i)) std::this_thread::yield();
    }
  });
  std::vector<long> got;
  while (got.size() < 300000u) {
    if (big.drain(got) == 0) std::this_thread::yield();
  }
  producer.join();
  for (long i = 0; i < 300000; ++i) ASSERT_EQ(got[std::size_t(i)], i);
}

TEST(HapticsDevices, ScriptedKeyframesInterpolateAndReportSilence) {
  ScriptedDevice d(
      ScriptedDevice::keyframes({{0.0, {0, 0, 0}}, {1.0, {1, 0, 0}}, {2.0, {1, 2, 0}}}));
  Eigen::Vector3d p;
  ASSERT_TRUE(d.read(0.5, p));
  EXPECT_EQ(p, Eigen::Vector3d(0.5, 0, 0));
  ASSERT_TRUE(d.read(1.5, p));
  EXPECT_EQ(p, Eigen::Vector3d(1, 1, 0));
  ASSERT_TRUE(d.read(5, p));
  EXPECT_EQ(p, Eigen::Vector3d(1, 2, 0));
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  EXPECT_THROW(ScriptedDevice::keyframes({{1.0, o}, {1.0, o}}), core::InputError);
  ScriptedDevice silent([](double t) -> std::optional<Eigen::Vector3d> {
    if (t > 1) return std::nullopt;
    return Eigen::Vector3d::Zero();
  });
  EXPECT_TRUE(silent.read(0.5, p));
  EXPECT_FALSE(silent.read(1.5, p));
}

TEST(HapticsDevices, TrackedMarkerIsContinuousOneFrameLateAndTimesOut) {
  TrackedMarkerDevice d(0.1);
  Eigen::Vector3d p;
  EXPECT_FALSE(d.read(0.0, p));  // nothing yet
  d.push({0, 0, 0}, 0.0);
  ASSERT_TRUE(d.read(0.01, p));
  EXPECT_EQ(p, Eigen::Vector3d::Zero());
  // 30 Hz samples along x at 0.3 m/s: read at 1 kHz, the path has no step above 1 tick's travel.
  const double fps = 30;
  Eigen::Vector3d prev = Eigen::Vector3d::Zero();
  double maxStep = 0;
  int frame = 1;
  for (int k = 1; k < 1000; ++k) {
    const double t = k * 1e-3;
    while (frame / fps <= t) {
      d.push({0.3 * frame / fps, 0, 0}, frame / fps);
      ++frame;
    }
    ASSERT_TRUE(d.read(t, p));
    maxStep = std::max(maxStep, (p - prev).norm());
    prev = p;
    // one frame late: x(t - 1/fps), within one tick's travel
    if (t > 2 / fps) {
      EXPECT_NEAR(p.x(), 0.3 * (t - 1 / fps), 0.3 * 1e-3 + 1e-12);
    }
  }
  EXPECT_LE(maxStep, 0.3 * 1e-3 * 1.0001);
  // No sample for longer than the timeout: not answering.
  EXPECT_FALSE(d.read(frame / fps + 0.2, p));
  // A lost marker (NaN) stops the device at once.
  d.push({haptictest::kNaN, 0, 0}, frame / fps + 0.01);
  EXPECT_FALSE(d.read(frame / fps + 0.011, p));
  EXPECT_THROW(TrackedMarkerDevice(0.0), core::InputError);
}

TEST(HapticsLog, WritesAndReadsBackEveryColumn) {
  std::stringstream s;
  ForceLogWriter w(s);
  ForceRecord a;
  a.time = 1.25;
  a.tipPlanet = {6372790.5, -12.25, 3.0};
  a.force = {0.5, -1.5, 2.25};
  a.depth = 0.00125;
  a.repulse = 2.5;
  a.damping = 10;
  a.ramp = 0.5;
  a.touching = true;
  ForceRecord b;
  b.time = 1.251;
  b.tipPlanet.setConstant(haptictest::kNaN);
  b.fault = Fault::kDeviceLost;
  w.write(a);
  w.write(b);
  EXPECT_EQ(w.rows(), 2u);
  const auto rs = readForceLog(s);
  ASSERT_EQ(rs.size(), 2u);
  EXPECT_EQ(rs[0].time, 1.25);
  EXPECT_EQ(rs[0].tipPlanet, a.tipPlanet);
  EXPECT_EQ(rs[0].force, a.force);
  EXPECT_EQ(rs[0].depth, a.depth);
  EXPECT_EQ(rs[0].ramp, 0.5);
  EXPECT_TRUE(rs[0].touching);
  EXPECT_FALSE(rs[1].tipPlanet.allFinite());
  EXPECT_EQ(rs[1].fault, Fault::kDeviceLost);
  std::stringstream bad("t,x\n1,2\n");
  EXPECT_THROW(readForceLog(bad), core::InputError);
}

TEST(HapticsCore, MapsDeviceSpaceToThePlanetAndForcesBack) {
  // A planet 6,372.79 km in radius shown as a 6 cm globe: 1.06e8 planet m per device m.
  const terrain::Terrain t = haptictest::reliefPlanet(8);
  WorkspaceMap map;
  map.scale = haptictest::kR / 0.06;
  const Eigen::Vector3d dir = haptictest::latLon(0, 0, 1);
  const double h = t.height(t.grid().m() / 2, t.grid().m() / 2);
  HapticCore core(HapticSettings{}, map);
  TerrainPatch p;
  ASSERT_TRUE(p.capture(t, dir * haptictest::kR, 8));
  // 1 mm (device) below the surface: 2 N with the paper's sand at the 2000 N/m limit.
  const Eigen::Vector3d tipDevice = dir * ((haptictest::kR + h) / map.scale - 0.001);
  ForceRecord r;
  for (int k = 0; k < 100; ++k) r = core.tick(k * 1e-3, true, tipDevice, &p);
  EXPECT_NEAR(r.depth, 0.001, 1e-9);
  EXPECT_NEAR((r.force - 2.0 * dir).norm(), 0.0, 1e-6);
  EXPECT_NEAR((r.tipPlanet - map.toPlanet(tipDevice)).norm(), 0.0, 1e-6);
  // No snapshot: zero force, no-terrain.
  r = core.tick(0.2, true, tipDevice, nullptr);
  EXPECT_EQ(r.fault, Fault::kNoTerrain);
  EXPECT_EQ(r.force, Eigen::Vector3d::Zero());
}

TEST(HapticsCore, NewSnapshotUnderATouchingToolIsBlendedNotStepped) {
  // Flat sand, 1 mm cells; the tool rests 2 mm deep; the editor then lowers the sand under it by
  // 1 mm (a displacement stamp). The force goes from 2000 N/m x 2 mm to x 1 mm over the 30 ms
  // blend, in equal steps, instead of at once.
  auto chart = sandtest::flatChart(6, 0.001, 0.001);
  terrain::Terrain t(chart, std::vector<float>(chart->grid().count(), 0.01f));
  HapticSettings s;
  HapticCore core(s, WorkspaceMap{});
  TerrainPatch a, b;
  const Eigen::Vector3d tip(0.032, 0.032, 0.008);
  ASSERT_TRUE(a.capture(t, tip, 8));
  ForceRecord r;
  double time = 0;
  for (int k = 0; k < 100; ++k) r = core.tick(time += 1e-3, true, tip, &a);
  EXPECT_NEAR(r.force.z(), 4.0, 1e-6);
  for (float& h : t.mutableHeights()) h = 0.009f;
  t.commitEdit(terrain::VertexBox::all(t.grid()));
  ASSERT_TRUE(b.capture(t, tip, 8));
  ASSERT_NE(a.serial(), b.serial());
  double prev = r.force.z(), maxStep = 0;
  for (int k = 1; k <= 40; ++k) {
    r = core.tick(time += 1e-3, true, tip, &b);
    maxStep = std::max(maxStep, std::abs(r.force.z() - prev));
    prev = r.force.z();
    if (k == 15) {
      EXPECT_NEAR(r.force.z(), 3.0, 0.1);  // half way
    }
  }
  EXPECT_NEAR(r.force.z(), 2.0, 1e-4);           // the new surface, fully
  EXPECT_LE(maxStep, 2.0 * 1e-3 / 0.03 + 1e-6);  // 2 N over 30 ms: 0.067 N per tick
  // Leaving the snapshot: no terrain, zero force.
  r = core.tick(time += 1e-3, true, tip + Eigen::Vector3d(0.0005, 0, 0), &b);
  EXPECT_EQ(r.fault, Fault::kNone);
  TerrainPatch small;
  ASSERT_TRUE(small.capture(t, tip, 2));
  const Eigen::Vector3d far = tip + Eigen::Vector3d(0.004, 0, 0.001);  // 4 cells: outside
  for (int k = 0; k < 3; ++k)
    r = core.tick(time += 1e-3, true, tip + Eigen::Vector3d(0.0008 * k, 0, 0.0003 * k), &small);
  r = core.tick(time += 1e-3, true, far, &small);
  EXPECT_EQ(r.fault, Fault::kNoTerrain);
  EXPECT_EQ(r.force, Eigen::Vector3d::Zero());
}
