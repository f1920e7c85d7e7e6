// The force law, the safety layer and the energy behaviour of the haptic path (src/haptics):
// ForceModel driven directly with analytic surfaces, no threads, no clocks.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "core/input_error.hpp"
#include "haptics/force_model.hpp"
#include "haptics/settings.hpp"
#include "test_haptics_util.hpp"

using namespace ps;
using namespace ps::haptics;

namespace {

// Expects an InputError whose message names `name`.
template <class F>
void expectNamed(F&& f, const std::string& name) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << name;
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos)
        << "message '" << e.what() << "' does not name " << name;
  }
}

}  // namespace

TEST(HapticsSettings, PaperConstantsConvertToDeviceUnits) {
  const ForceConstants c = ForceConstants::fromPaper(1e3, 0.5, 10.0, 0.1);
  EXPECT_DOUBLE_EQ(c.ks, 1000.0);  // N
  EXPECT_DOUBLE_EQ(c.kc, 5.0);     // 1/m
  EXPECT_DOUBLE_EQ(c.kf, 100.0);   // s/m
  EXPECT_EQ(ForceConstants::paperSand(), c);
  EXPECT_EQ(HapticSettings{}.constants, c);
  // Linearised stiffness of the paper's sand at the surface: k_s k_c = 5000 N/m, above the
  // default device's 2000 N/m: the clamp binds from the surface on.
  const RepulseLaw law(c, DeviceLimits{});
  EXPECT_LT(law.kneeDepth(), 0.0);
  EXPECT_DOUBLE_EQ(law(1e-3), 2.0);
}

TEST(HapticsSettings, BadConstantsAndRatesNameTheParameter) {
  auto with = [](auto edit) {
    HapticSettings s;
    edit(s);
    return s;
  };
  expectNamed([&] { with([](HapticSettings& s) { s.constants.ks = 0; }).validate(); }, "k_s");
  expectNamed([&] { with([](HapticSettings& s) { s.constants.ks = -1e3; }).validate(); }, "k_s");
  expectNamed([&] { with([](HapticSettings& s) { s.constants.kc = -0.5; }).validate(); }, "k_c");
  expectNamed(
      [&] { with([](HapticSettings& s) { s.constants.kc = haptictest::kInf; }).validate(); },
      "k_c");
  expectNamed(
      [&] { with([](HapticSettings& s) { s.constants.kf = haptictest::kNaN; }).validate(); },
      "k_f");
  expectNamed([&] { with([](HapticSettings& s) { s.rateHz = 99.9; }).validate(); }, "rate");
  expectNamed([&] { with([](HapticSettings& s) { s.rateHz = 10001; }).validate(); }, "rate");
  expectNamed([&] { with([](HapticSettings& s) { s.rateHz = haptictest::kNaN; }).validate(); },
              "rate");
  expectNamed([&] { with([](HapticSettings& s) { s.limits.maxForce = 0; }).validate(); },
              "max force");
  expectNamed([&] { with([](HapticSettings& s) { s.limits.maxStiffness = -1; }).validate(); },
              "max stiffness");
  expectNamed(
      [&] { with([](HapticSettings& s) { s.limits.maxDamping = haptictest::kNaN; }).validate(); },
      "max damping");
  expectNamed([&] { with([](HapticSettings& s) { s.limits.maxForceRate = 0; }).validate(); },
              "max force rate");
  expectNamed([&] { with([](HapticSettings& s) { s.safety.rampTime = -0.1; }).validate(); },
              "ramp time");
  expectNamed([&] { with([](HapticSettings& s) { s.safety.maxSpeed = 0; }).validate(); },
              "max speed");
  expectNamed(
      [&] {
        with([](HapticSettings& s) {
          s.rateHz = 100;
          s.safety.velocityCutoffHz = 60;  // above rate / 2
        }).validate();
      },
      "velocity cut-off");
  expectNamed([] { ForceConstants::fromPaper(1e3, 0.5, 10, 0); }, "paper unit");
  expectNamed([] { WorkspaceMap{.scale = 0}.validate(); }, "workspace scale");
  expectNamed(
      [] {
        WorkspaceMap m;
        m.rotation(0, 0) = -1;  // a reflection
        m.validate();
      },
      "workspace rotation");
  // The model refuses them too, before any tick.
  expectNamed([&] { ForceModel(with([](HapticSettings& s) { s.rateHz = 50; })); }, "rate");
  // The ends of the range are fine.
  for (double rate : {100.0, 1000.0, 10000.0})
    EXPECT_NO_THROW(with([&](HapticSettings& s) { s.rateHz = rate; }).validate());
}

TEST(HapticsModel, RepulseLawFollowsPaperUntilStiffnessLimitThenLinear) {
  HapticSettings s = haptictest::softSand();
  s.limits.maxForce = 100;  // above the knee's 18 N
  const RepulseLaw law(s.constants, s.limits);
  const double knee = std::log(2000.0 / 200.0) / 100.0;
  EXPECT_NEAR(law.kneeDepth(), knee, 1e-15);
  EXPECT_EQ(law(0.0), 0.0);
  EXPECT_EQ(law(-1.0), 0.0);
  EXPECT_EQ(law(haptictest::kNaN), 0.0);
  EXPECT_EQ(law(-haptictest::kInf), 0.0);
  EXPECT_EQ(law(haptictest::kInf), s.limits.maxForce);
  for (double d = 1e-4; d < knee; d += 1e-3)
    EXPECT_NEAR(law(d), 2.0 * std::expm1(100.0 * d), 1e-12);  // the paper's eq. (1)
  // Beyond the knee: continuous, slope exactly the limit, up to the force limit.
  const double fk = 2.0 * std::expm1(100.0 * knee);
  EXPECT_NEAR(law(knee + 1e-3), fk + 2.0, 1e-9);
  double prev = 0;
  for (double d = 0; d < 0.05; d += 1e-5) {
    const double f = law(d);
    EXPECT_LE(f, 2.0 * std::expm1(100.0 * d) + 1e-12);  // never above the paper's law
    EXPECT_LE(f, s.limits.maxForce);
    EXPECT_GE(f, prev);                                              // monotone
    EXPECT_LE(f - prev, s.limits.maxStiffness * 1e-5 * (1 + 1e-9));  // slope <= K
    prev = f;
  }
}

TEST(HapticsModel, ZeroForceAboveTheSurface) {
  ForceModel model(haptictest::softSand());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(-4e-4, 4e-4);
  // Push in first, so that the ramp is full and the velocity filter is moving: above the surface
  // the force must still be exactly zero.
  double t = 0;
  TickOutput o;
  for (int k = 0; k <= 100; ++k)
    o = model.tick(haptictest::flatInput(t += 1e-3, {0, 0, -1e-4 * k}));
  EXPECT_GT(o.force.norm(), 1.0);
  EXPECT_EQ(o.ramp, 1.0);
  Eigen::Vector3d p(0, 0, -0.01);
  for (int k = 0; k < 20; ++k)
    o = model.tick(haptictest::flatInput(t += 1e-3, p += Eigen::Vector3d(0, 0, 5.5e-4)));
  EXPECT_GT(p.z(), 0.0);
  // A random walk above the surface and exactly on it (z = 0 every 97th tick).
  for (int k = 0; k < 20000; ++k) {
    p += Eigen::Vector3d(step(rng), step(rng), step(rng));
    p.z() = k % 97 == 0 ? 0.0 : std::clamp(p.z(), 0.0, 0.002);
    o = model.tick(haptictest::flatInput(t += 1e-3, p));
    ASSERT_EQ(o.fault, Fault::kNone) << "tick " << k;
    ASSERT_FALSE(o.touching) << p.transpose();
    ASSERT_EQ(o.force, Eigen::Vector3d::Zero()) << "tick " << k << " at " << p.transpose();
    ASSERT_EQ(o.repulse, 0.0);
  }
}

TEST(HapticsModel, ForceIsContinuousAlongAContinuousPath) {
  // A smooth path that dips in and out of the sand and sweeps sideways: per tick the force may
  // change by at most
  //   K |dd| (1 + k_f |v|) + B |dv| + F_max dt / T_ramp      (K, B, F_max: the device limits)
  // (the repulse law's slope is at most K; the damping min(k_f F_r, B) changes by at most
  // k_f K |dd| and multiplies |v|; the ramp adds at most F_max dt / T; the force clamp is a
  // projection, which does not increase differences).
  for (const HapticSettings& s : {haptictest::softSand(), HapticSettings{}}) {
    ForceModel model(s);
    const double dt = s.period();
    const DeviceLimits& L = s.limits;
    TickOutput prev;
    double worstRatio = 0, worstStep = 0;
    int touching = 0;
    for (int k = 0; k < 6000; ++k) {
      const double t = k * dt;
      const Eigen::Vector3d p(0.03 * std::sin(2.1 * t), 0.02 * std::cos(1.3 * t),
                              0.002 - 0.006 * std::sin(3.0 * t) * std::sin(3.0 * t));
      const TickOutput o = model.tick(haptictest::flatInput(t, p));
      ASSERT_EQ(o.fault, Fault::kNone);
      ASSERT_FALSE(o.slewLimited) << "tick " << k;
      touching += o.touching;
      if (k > 0) {
        const double step = (o.force - prev.force).norm();
        const double bound =
            L.maxStiffness * std::abs(o.depth - prev.depth) *
                (1 + s.constants.kf * std::max(o.velocity.norm(), prev.velocity.norm())) +
            L.maxDamping * (o.velocity - prev.velocity).norm() +
            L.maxForce * dt / s.safety.rampTime + 1e-12;
        ASSERT_LE(step, bound) << "tick " << k;
        worstRatio = std::max(worstRatio, step / bound);
        worstStep = std::max(worstStep, step);
      }
      prev = o;
    }
    EXPECT_GT(touching, 1000);  // the path really was in the sand
    // On this path (|v| <= 0.07 m/s) no tick changed the force by more than 0.3 N.
    EXPECT_LT(worstStep, 0.3);
    RecordProperty("worst_step_over_bound", std::to_string(worstRatio));
  }
}

TEST(HapticsModel, ClampsHoldForAnyInputIncludingNaNAndTeleports) {
  HapticSettings s = haptictest::softSand();
  s.limits.maxForce = 5.0;
  s.limits.maxForceRate = 1000.0;
  ForceModel model(s);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u01(0.0, 1.0), sym(-1.0, 1.0);
  const double specials[] = {
      haptictest::kNaN, haptictest::kInf, -haptictest::kInf, 1e300, -1e300, 0.0, 1e-300};
  auto pick = [&](double normal) {
    const double r = u01(rng);
    if (r < 0.05) return specials[std::size_t(u01(rng) * 7) % 7];
    return normal;
  };
  double t = 0;
  Eigen::Vector3d p(0, 0, -0.002);
  Eigen::Vector3d lastForce = Eigen::Vector3d::Zero();
  int faults = 0, teleports = 0, loaded = 0;
  for (int k = 0; k < 200000; ++k) {
    TickInput in;
    // Time mostly advancing by a period, sometimes stalling, jumping or going back.
    const double r = u01(rng);
    t += r < 0.9 ? 1e-3 : (r < 0.95 ? 0.05 * u01(rng) : -1e-3);
    in.time = pick(t);
    // Position: a walk inside the sand, with teleports and garbage.
    const double q = u01(rng);
    if (q < 0.01) {
      p += Eigen::Vector3d(sym(rng), sym(rng), sym(rng));  // teleport by up to a metre
      ++teleports;
    } else {
      p += 2e-4 * Eigen::Vector3d(sym(rng), sym(rng), sym(rng));
      p.z() = std::clamp(p.z(), -0.2, 0.01);
    }
    in.position = Eigen::Vector3d(pick(p.x()), pick(p.y()), pick(p.z()));
    in.deviceOk = u01(rng) > 0.01;
    in.contact.valid = u01(rng) > 0.01;
    in.contact.depth = pick(u01(rng) < 0.02 ? 1e6 * sym(rng) : -p.z());
    in.contact.normal =
        u01(rng) < 0.02 ? Eigen::Vector3d(sym(rng), pick(sym(rng)), 3.0) : Eigen::Vector3d::UnitZ();
    const TickOutput o = model.tick(in);
    ASSERT_TRUE(o.force.allFinite()) << "tick " << k;
    ASSERT_LE(o.force.norm(), s.limits.maxForce * (1 + 1e-12)) << "tick " << k;
    ASSERT_GE(o.ramp, 0.0);
    ASSERT_LE(o.ramp, 1.0);
    ASSERT_LE(o.damping, s.limits.maxDamping);
    if (o.fault != Fault::kNone) {
      ++faults;
      ASSERT_EQ(o.force, Eigen::Vector3d::Zero()) << "fault " << toString(o.fault);
      ASSERT_EQ(o.ramp, 0.0);
    }
    const bool garbage = !in.deviceOk || !in.position.allFinite() || !std::isfinite(in.time);
    if (garbage) {
      ASSERT_NE(o.fault, Fault::kNone) << "tick " << k;
    }
    // Growth per tick is limited (dt is capped at 4 periods), release is free.
    if (o.force.norm() > lastForce.norm()) {
      ASSERT_LE((o.force - lastForce).norm(), s.limits.maxForceRate * 4e-3 * (1 + 1e-9));
    }
    if (o.force.norm() > 1.0) ++loaded;
    lastForce = o.force;
  }
  EXPECT_GT(faults, 1000);
  EXPECT_GT(teleports, 1000);
  EXPECT_GT(loaded, 1000);  // the clamps were exercised, not just zero forces
}

TEST(HapticsModel, TeleportGivesZeroForceThenRampsBackIn) {
  HapticSettings s = haptictest::softSand();
  ForceModel model(s);
  double t = 0;
  TickOutput o;
  for (int k = 0; k < 300; ++k) o = model.tick(haptictest::flatInput(t += 1e-3, {0, 0, -0.01}));
  EXPECT_EQ(o.ramp, 1.0);
  const double full = o.force.norm();
  EXPECT_NEAR(full, 2.0 * std::expm1(1.0), 1e-9);
  // 5 cm in one tick (50 m/s): a jump.
  o = model.tick(haptictest::flatInput(t += 1e-3, {0.05, 0, -0.01}));
  EXPECT_EQ(o.fault, Fault::kJump);
  EXPECT_EQ(o.force, Eigen::Vector3d::Zero());
  // NaN: zero.
  o = model.tick(haptictest::flatInput(t += 1e-3, {haptictest::kNaN, 0, -0.01}));
  EXPECT_EQ(o.fault, Fault::kNonFinite);
  EXPECT_EQ(o.force, Eigen::Vector3d::Zero());
  // Back at the same depth: the force comes back over the ramp time, never a kick.
  double prevF = 0;
  for (int k = 1; k <= 60; ++k) {
    o = model.tick(haptictest::flatInput(t += 1e-3, {0.05, 0, -0.01}));
    ASSERT_EQ(o.fault, Fault::kNone);
    EXPECT_NEAR(o.force.norm(), std::min(1.0, k * 1e-3 / s.safety.rampTime) * full, 1e-9);
    EXPECT_LE(o.force.norm() - prevF, full * 1e-3 / s.safety.rampTime + 1e-12);
    prevF = o.force.norm();
  }
}

namespace {

struct EnergyResult {
  double work = 0;        // done by the device on the hand over the path (J): > 0 = injected
  double zohBound = 0;    // sum 1/2 |dF_r| |dd|: what holding a convex law for a tick may inject
  double peakEnergy = 0;  // integral of the law to the deepest point (J)
  double rampBound = 0;   // energy stored when the ramp completed (J)
};

// A push-and-pull script: `cycles` times straight down to `depth` and back out over `period`
// seconds, drifting sideways (the drag sees a lateral velocity too).
EnergyResult pushAndPull(const HapticSettings& s, double depth, double period, int cycles) {
  ForceModel model(s);
  const double dt = s.period();
  const RepulseLaw law(s.constants, s.limits);
  EnergyResult e;
  const int n = int(std::lround(cycles * period / dt));
  Eigen::Vector3d x0;
  TickOutput o0;
  double maxD = 0;
  bool rampDone = false;
  for (int k = 0; k <= n; ++k) {
    const double t = k * dt;
    const double ph = std::sin(std::numbers::pi * t / period);
    const Eigen::Vector3d x(0.01 * std::sin(0.5 * t), 0.0, 0.001 - (depth + 0.001) * ph * ph);
    const TickOutput o = model.tick(haptictest::flatInput(t, x));
    EXPECT_EQ(o.fault, Fault::kNone);
    if (k > 0) {
      e.work += o0.force.dot(x - x0);  // zero-order hold: o0.force acts while moving x0 -> x
      e.zohBound += 0.5 * std::abs(law(o.depth) - law(o0.depth)) *
                    std::abs(std::max(o.depth, 0.0) - std::max(o0.depth, 0.0));
    }
    maxD = std::max(maxD, o.depth);
    if (!rampDone && o.ramp >= 1.0) {
      rampDone = true;
      for (int i = 1; i <= 1000; ++i)
        e.rampBound += law(o.depth * (i - 0.5) / 1000) * o.depth / 1000;
    }
    x0 = x;
    o0 = o;
  }
  for (int i = 1; i <= 10000; ++i) e.peakEnergy += law(maxD * (i - 0.5) / 10000) * maxD / 10000;
  return e;
}

}  // namespace

TEST(HapticsEnergy, PushAndPullInjectsNoNetEnergy) {
  // Tolerance. The law is sampled once per tick and held: pushing in, the held force is the one
  // at the shallower end of the step, pulling out the one at the deeper end, so a convex law
  // returns up to 1/2 |dF_r| |dd| per tick more than it took (for a linear law exactly that: the
  // work of a damper of K T / 2 = 1 N s/m at K = 2000 N/m, T = 1 ms, which a device's own
  // friction absorbs). The ramp may add at most the energy stored when it completes. Without
  // drag the net work must stay within that sum; with the paper's drag it must be negative.
  for (bool drag : {false, true}) {
    for (const HapticSettings& base : {haptictest::softSand(), HapticSettings{}}) {
      HapticSettings s = base;
      if (!drag) s.constants.kf = 1e-12;  // conservative law alone
      const EnergyResult e = pushAndPull(s, 0.004, 1.0, 5);
      const double tolerance = e.zohBound + e.rampBound;
      EXPECT_GT(e.peakEnergy, 1e-3);
      EXPECT_LE(e.work, tolerance)
          << "drag " << drag << ": work " << e.work << " J, peak " << e.peakEnergy << " J";
      if (drag) {
        EXPECT_LT(e.work, 0.0);  // the drag dissipates: the hand loses energy
      }
      std::cerr << "energy: drag " << drag << " ks " << s.constants.ks << ": net work " << e.work
                << " J, tolerance " << tolerance << " J, peak stored " << e.peakEnergy
                << " J over 5 cycles\n";
    }
  }
}
