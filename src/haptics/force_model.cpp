#include "haptics/force_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/named_values.hpp"

namespace ps::haptics {

namespace {
constexpr core::NameTable<Fault, 6> kFaults{"fault",
                                            {{{Fault::kNone, "none"},
                                              {Fault::kDeviceLost, "device-lost"},
                                              {Fault::kNonFinite, "non-finite"},
                                              {Fault::kJump, "jump"},
                                              {Fault::kTimeOrder, "time-order"},
                                              {Fault::kNoTerrain, "no-terrain"}}}};
}  // namespace

const char* toString(Fault f) {
  return kFaults.nameOf(f);
}

Fault faultFromString(const std::string& s) {
  return kFaults.parse(s);
}

RepulseLaw::RepulseLaw(const ForceConstants& c, const DeviceLimits& limits)
    : ks_(c.ks), kc_(c.kc), stiffness_(limits.maxStiffness), maxForce_(limits.maxForce) {
  // k_s k_c e^{k_c d*} = K  =>  d* = ln(K / (k_s k_c)) / k_c
  knee_ = std::log(stiffness_ / (ks_ * kc_)) / kc_;
  kneeForce_ = knee_ > 0 ? ks_ * std::expm1(kc_ * knee_) : 0.0;
}

double RepulseLaw::operator()(double d) const {
  if (!(d > 0)) return 0.0;  // above the surface, and NaN
  double f;
  if (knee_ <= 0) {
    f = stiffness_ * d;
  } else if (d <= knee_) {
    f = ks_ * std::expm1(kc_ * d);
  } else {
    f = kneeForce_ + stiffness_ * (d - knee_);
  }
  return std::min(f, maxForce_);
}

ForceModel::ForceModel(const HapticSettings& settings)
    : settings_((settings.validate(), settings)),
      law_(settings.constants, settings.limits),
      dtNominal_(settings.period()) {}

void ForceModel::reset() {
  have_ = false;
  vel_.setZero();
  lastForce_.setZero();
  ramp_ = 0;
}

TickOutput ForceModel::zero(const TickInput& in, Fault f) {
  TickOutput o;
  o.time = in.time;
  o.fault = f;
  ++faults_;
  lastForce_.setZero();
  ramp_ = 0;
  return o;
}

TickOutput ForceModel::tick(const TickInput& in) {
  if (!in.deviceOk) {
    reset();
    return zero(in, Fault::kDeviceLost);
  }
  if (!std::isfinite(in.time) || !in.position.allFinite()) {
    reset();
    return zero(in, Fault::kNonFinite);
  }
  if (have_ && !(in.time > lastTime_)) {
    reset();
    return zero(in, Fault::kTimeOrder);
  }
  const double dtRaw = have_ ? in.time - lastTime_ : dtNominal_;
  if (have_ &&
      (in.position - lastPos_).norm() > settings_.safety.maxSpeed * std::max(dtRaw, dtNominal_)) {
    reset();
    have_ = true;  // the new position is the new reference
    lastTime_ = in.time;
    lastPos_ = in.position;
    return zero(in, Fault::kJump);
  }
  // Velocity: first-order low-pass of the difference quotient. dt is capped at 4 periods so a
  // stalled loop neither freezes the filter nor lets one sample dominate it.
  const double dt = std::min(dtRaw, 4 * dtNominal_);
  if (have_) {
    const Eigen::Vector3d raw = (in.position - lastPos_) / dtRaw;
    const double alpha =
        -std::expm1(-2 * std::numbers::pi * settings_.safety.velocityCutoffHz * dt);
    vel_ += alpha * (raw - vel_);
  }
  have_ = true;
  lastTime_ = in.time;
  lastPos_ = in.position;

  const Contact& c = in.contact;
  if (!c.valid || !std::isfinite(c.depth) || !c.normal.allFinite() ||
      std::abs(c.normal.norm() - 1) > 1e-6) {
    TickOutput o = zero(in, Fault::kNoTerrain);
    o.velocity = vel_;
    return o;
  }

  const DeviceLimits& lim = settings_.limits;
  TickOutput o;
  o.time = in.time;
  o.velocity = vel_;
  o.depth = c.depth;
  o.touching = c.depth > 0;
  if (o.touching) {
    const double T = settings_.safety.rampTime;
    ramp_ = T > 0 ? std::min(1.0, ramp_ + dt / T) : 1.0;
    o.repulse = law_(c.depth);
    o.damping = std::min(settings_.constants.kf * o.repulse, lim.maxDamping);
    Eigen::Vector3d f = ramp_ * (o.repulse * c.normal - o.damping * vel_);
    const double n = f.norm();
    if (n > lim.maxForce) f *= lim.maxForce / n;
    // Growth limit: |F| may grow by at most maxForceRate * dt per tick; shrinking is immediate.
    const double grow = lim.maxForceRate * dt;
    const Eigen::Vector3d step = f - lastForce_;
    if (f.norm() > lastForce_.norm() && step.norm() > grow) {
      f = lastForce_ + step * (grow / step.norm());
      o.slewLimited = true;
    }
    o.force = f;
  }
  o.ramp = ramp_;
  lastForce_ = o.force;
  return o;
}

}  // namespace ps::haptics
