// The force path: offline per-frame stepping (what a replay calls), presses through the edit
// pipeline, lost tracking, and the live 1 kHz thread beside an editor loop (no timing asserted).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "core/input_error.hpp"
#include "core/octahedral_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "haptics/force_path.hpp"
#include "sand/sand_grid.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"
#include "test_haptics_util.hpp"
#include "test_sand_util.hpp"

using namespace ps;
using namespace ps::haptics;

namespace {

Eigen::Vector3d dirAt(double latDeg, double lonDeg) {
  return haptictest::latLon(latDeg, lonDeg);
}

ForcePathConfig globeConfig() {
  ForcePathConfig c;
  c.map.scale = haptictest::kR / haptictest::kGlobe;
  return c;
}

// The demo-like stroke, in the planet frame: down from 3 mm (device) above the surface to
// `depth` below it in 1 s, dragged 5 degrees east in 1 s, back up in 1 s.
Eigen::Vector3d strokeTip(double t, double surfaceR, double depthDevice) {
  const double scale = haptictest::kR / haptictest::kGlobe;
  const double above = 0.003 * scale, below = -depthDevice * scale;
  double alt, lon = 40;
  if (t < 1) {
    alt = above + (below - above) * t;
  } else if (t < 2) {
    alt = below;
    lon += 5 * (t - 1);
  } else {
    alt = below + (above - below) * std::min(1.0, t - 2);
    lon += 5;
  }
  return dirAt(20, lon) * (surfaceR + alt);
}

struct StrokeRun {
  std::string log;
  std::vector<float> heights;
  std::vector<FrameForces> frames;
  std::uint64_t stamps = 0;
};

StrokeRun runStroke(double depthDevice, const std::function<bool(double)>& tracked = {}) {
  terrain::Terrain t = haptictest::flatPlanet(9);
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  ForcePath s(t, &pipe, globeConfig());
  std::ostringstream log;
  s.setLog(&log);
  StrokeRun r;
  for (int f = 0; f <= 90; ++f) {
    const double time = f / 30.0;
    std::optional<Eigen::Vector3d> tip = strokeTip(time, haptictest::kR + 2000.0, depthDevice);
    if (tracked && !tracked(time)) tip.reset();
    r.frames.push_back(s.onFrame(tip, time));
  }
  r.log = log.str();
  r.heights.assign(t.heights().begin(), t.heights().end());
  r.stamps = s.totalStamps();
  return r;
}

}  // namespace

TEST(HapticsForcePath, ReplayStrokeIsLoggedDeterministicallyAndSculptsThroughThePipeline) {
  const StrokeRun a = runStroke(0.0015);
  std::istringstream in(a.log);
  const std::vector<ForceRecord> rs = readForceLog(in);
  ASSERT_EQ(rs.size(), 3001u);  // t = 0 .. 3 s at 1 kHz, each tick once
  int touching = 0;
  double maxF = 0;
  for (std::size_t k = 0; k < rs.size(); ++k) {
    const ForceRecord& r = rs[k];
    EXPECT_NEAR(r.time, double(k) / 1000, 1e-9);
    ASSERT_LE(r.force.norm(), HapticSettings{}.limits.maxForce + 1e-9);
    if (!r.touching) {
      EXPECT_EQ(r.force, Eigen::Vector3d::Zero()) << "t = " << r.time;
    }
    touching += r.touching;
    maxF = std::max(maxF, r.force.norm());
    if (k > 0) {
      EXPECT_LE((r.force - rs[k - 1].force).norm(), 0.5) << "t = " << r.time;
    }
  }
  EXPECT_GT(touching, 1000);
  EXPECT_GT(maxF, 1.0);
  EXPECT_GT(a.stamps, 3u);
  // The displacement keeps volume (sand/displacement.hpp), and moved something.
  auto chart = sandtest::sphereChart(9, haptictest::kR);
  const sand::SandGrid grid(chart);
  const terrain::Terrain before = haptictest::flatPlanet(9);
  const double v0 = grid.volume(before.heights()), v1 = grid.volume(a.heights);
  double moved = 0;
  for (std::size_t i = 0; i < a.heights.size(); ++i)
    moved += std::abs(double(a.heights[i]) - before.heights()[i]);
  EXPECT_GT(moved, 1e5);
  EXPECT_LT(std::abs(v1 - v0) / grid.absVolume(before.heights()), 1e-6);
  // Same input, same log and planet, bit for bit.
  const StrokeRun b = runStroke(0.0015);
  EXPECT_EQ(a.log, b.log);
  EXPECT_EQ(a.heights, b.heights);
}

TEST(HapticsForcePath, PressesAcrossAFoldOfTheOctahedralChart) {
  // The demo-like stroke dragged across the fold u = 0 of an octahedral planet (513^2, 2 km of
  // sand): forces felt, sand displaced on both sides of the fold, the volume kept, twins one
  // height, the same log and planet twice.
  auto chart = std::make_shared<core::OctahedralChart>(core::GridSize(9), haptictest::kR);
  const int m = chart->grid().m();
  const Eigen::Vector3d c = chart->up(0, m / 4);
  const Eigen::Vector3d across = (chart->up(1, m / 4) - chart->up(1, m - m / 4)).normalized();
  auto run = [&] {
    return haptictest::pressDragLift(
        chart, 2000.0f, haptictest::kR / haptictest::kGlobe, [&](double alt, double x) {
          const Eigen::Vector3d dir = (c + 0.03 * x * across).normalized();  // +-1.7 degrees
          return Eigen::Vector3d(dir * (haptictest::kR + 2000.0 + alt));
        });
  };
  const haptictest::StrokeOutcome a = run();
  EXPECT_GT(a.touching, 1000);
  EXPECT_GT(a.maxForce, 1.0);
  EXPECT_LT(a.volumeDrift, 1e-6);
  const core::GridSize g = chart->grid();
  auto changedNear = [&](int u0, int v0) {
    int n = 0;
    for (int v = v0 - 8; v <= v0 + 8; ++v) {
      for (int u = u0; u <= u0 + 8; ++u) n += a.heights[g.index(u, v)] != 2000.0f;
    }
    return n;
  };
  EXPECT_GT(changedNear(1, m / 4), 0);      // this side of the fold
  EXPECT_GT(changedNear(1, m - m / 4), 0);  // across it
  const haptictest::StrokeOutcome b = run();
  EXPECT_EQ(a.log, b.log);
  EXPECT_EQ(a.heights, b.heights);
}

TEST(HapticsForcePath, DeeperPushesMoveMoreSand) {
  const terrain::Terrain base = haptictest::flatPlanet(9);
  auto removed = [&](const StrokeRun& r) {
    double sum = 0;
    for (std::size_t i = 0; i < r.heights.size(); ++i)
      sum += std::max(0.0, double(base.heights()[i]) - r.heights[i]);
    return sum;
  };
  const double shallow = removed(runStroke(0.0005)), deep = removed(runStroke(0.0015));
  EXPECT_GT(shallow, 0.0);
  EXPECT_GT(deep, 1.5 * shallow);
}

TEST(HapticsForcePath, LostTrackingGivesZeroForceAndTheSessionContinues) {
  // The marker is not seen from 1.3 s to 1.7 s (mid-drag; last seen at 38/30 s): 0.2 s later the
  // device stops answering, forces are zero, then they ramp back in and sculpting goes on.
  const StrokeRun r = runStroke(0.0015, [](double t) { return t < 1.3 || t > 1.7; });
  std::istringstream in(r.log);
  const auto rs = readForceLog(in);
  int lost = 0, after = 0;
  for (const ForceRecord& x : rs) {
    if (x.fault == Fault::kDeviceLost && x.time > 0) {  // t = 0: before the first sample
      ++lost;
      EXPECT_EQ(x.force, Eigen::Vector3d::Zero());
      EXPECT_GT(x.time, 38 / 30.0 + 0.2);
      EXPECT_LE(x.time, 52 / 30.0);
    }
    if (x.time > 1.85 && x.time < 2.0 && x.touching && x.force.norm() > 1.0) ++after;
  }
  EXPECT_GT(lost, 100);
  EXPECT_GT(after, 50);
  bool noted = false;
  for (const FrameForces& f : r.frames) {
    for (const std::string& n : f.notes) noted |= n.find("device-lost") != std::string::npos;
  }
  EXPECT_TRUE(noted);
  EXPECT_GT(r.stamps, 3u);
}

TEST(HapticsForcePath, BadConfigurationNamesTheParameter) {
  terrain::Terrain t = haptictest::flatPlanet(9);
  auto expectNamed = [&](ForcePathConfig c, const std::string& name) {
    try {
      ForcePath s(t, nullptr, c);
      ADD_FAILURE() << "no InputError for " << name;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  ForcePathConfig c = globeConfig();
  c.haptics.rateHz = 20000;
  expectNamed(c, "rate");
  c = globeConfig();
  c.haptics.constants.kc = 0;
  expectNamed(c, "k_c");
  c = globeConfig();
  c.press.yield = 0;
  expectNamed(c, "press yield");
  c = globeConfig();
  c.patchRadius = -1;
  expectNamed(c, "patch radius");
  c = globeConfig();
  c.map.scale = std::numeric_limits<double>::quiet_NaN();
  expectNamed(c, "workspace scale");
  // A non-finite frame time is a note, not an exception.
  ForcePath s(t, nullptr, globeConfig());
  const FrameForces f = s.onFrame(Eigen::Vector3d(haptictest::kR, 0, 0), std::nan(""));
  EXPECT_EQ(f.ticks, 0);
  EXPECT_FALSE(f.notes.empty());
}

TEST(HapticsLoop, LiveThreadFeedsTheEditorWithoutEditingItself) {
  terrain::Terrain t = haptictest::flatPlanet(9);
  edit::EditPipeline pipe(t);
  pipe.setUndoEnabled(false);
  ForcePath s(t, &pipe, globeConfig());
  const double scale = haptictest::kR / haptictest::kGlobe;
  const double surface = (haptictest::kR + 2000.0) / scale;  // device metres from the centre
  const Eigen::Vector3d d0 = dirAt(20, 40), d1 = dirAt(20, 41);
  // Device script (device frame = planet frame / scale): hover, press 1 mm in, drag, lift.
  ScriptedDevice device(ScriptedDevice::keyframes({{0.0, d0 * (surface + 0.002)},
                                                   {0.2, d0 * (surface - 0.001)},
                                                   {0.6, d1 * (surface - 0.001)},
                                                   {0.8, d1 * (surface + 0.002)}}));
  s.focus(d0 * (haptictest::kR + 2000.0));
  LoopOptions opt;
  opt.realtimePriority = false;
  opt.tickClock = true;  // the device's time is ticks x 1 ms: a loaded machine cannot skip any
  s.startLoop(device, opt);
  std::vector<FrameForces> frames;
  double lastTime = -1;
  std::uint64_t rev = t.revision();
  // Editor frames every 10 loop ticks, for 1,000 ticks: what the loop has done ends the test, not
  // a clock. On the tick clock the 1,000th tick is at 1.0 s, past the script's 0.8 s, and the
  // press covers ticks 200-800 however loaded the machine (the wall clock would skip missed
  // periods' time).
  constexpr std::uint64_t kTicks = 1000;
  std::uint64_t seen = 0;
  while (seen < kTicks) {
    s.loop()->waitForTicks(seen + 10);
    seen = s.loop()->stats().ticks;
    // Between editor frames the terrain does not change: the loop never edits.
    EXPECT_EQ(t.revision(), rev);
    frames.push_back(s.editorFrame());
    rev = t.revision();
    if (frames.back().last) {
      EXPECT_GT(frames.back().last->time, lastTime);
      lastTime = frames.back().last->time;
    }
  }
  const LoopStats st = s.loop()->stats();
  s.stopLoop();
  EXPECT_GT(st.ticks, 100u);  // however loaded the machine, it ticked
  EXPECT_EQ(st.droppedRecords, 0u);
  int touching = 0;
  double maxF = 0;
  for (const FrameForces& f : frames) {
    touching += f.touchingTicks;
    maxF = std::max(maxF, f.maxForce);
  }
  EXPECT_GT(touching, 10);
  EXPECT_GT(maxF, 0.5);
  EXPECT_LE(maxF, HapticSettings{}.limits.maxForce + 1e-9);
  EXPECT_GT(s.totalStamps(), 0u);
  EXPECT_GT(device.commands(), 100u);
  EXPECT_EQ(device.lastForce(), Eigen::Vector3d::Zero());  // stopped: zero force commanded
}
