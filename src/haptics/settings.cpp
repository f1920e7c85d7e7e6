#include "haptics/settings.hpp"

#include <Eigen/LU>
#include <cmath>
#include <sstream>

#include "core/input_error.hpp"

namespace ps::haptics {

namespace {

void require(bool ok, const char* name, double value, const char* unit, const char* rule) {
  if (ok) return;
  std::ostringstream s;
  s << "haptics: " << name << " = " << value << (unit[0] ? " " : "") << unit << " " << rule;
  throw core::InputError(s.str());
}

bool positive(double x) {
  return std::isfinite(x) && x > 0;
}

}  // namespace

ForceConstants ForceConstants::fromPaper(double ks, double kc, double kf, double paperUnitM) {
  require(positive(paperUnitM), "paper unit", paperUnitM, "m", "must be finite and > 0");
  ForceConstants c{ks, kc / paperUnitM, kf / paperUnitM};
  c.validate();
  return c;
}

void ForceConstants::validate() const {
  require(positive(ks), "k_s", ks, "N", "must be finite and > 0");
  require(positive(kc), "k_c", kc, "1/m", "must be finite and > 0");
  require(positive(kf), "k_f", kf, "s/m", "must be finite and > 0");
}

void DeviceLimits::validate() const {
  require(positive(maxForce) && maxForce <= 1000, "max force", maxForce, "N",
          "must be in (0, 1000]");
  require(positive(maxStiffness) && maxStiffness <= 1e6, "max stiffness", maxStiffness, "N/m",
          "must be in (0, 1e6]");
  require(positive(maxDamping) && maxDamping <= 1e4, "max damping", maxDamping, "N s/m",
          "must be in (0, 1e4]");
  require(positive(maxForceRate), "max force rate", maxForceRate, "N/s", "must be finite and > 0");
}

void SafetySettings::validate(double rateHz) const {
  require(std::isfinite(rampTime) && rampTime >= 0 && rampTime <= 5, "ramp time", rampTime, "s",
          "must be in [0, 5]");
  require(positive(maxSpeed) && maxSpeed <= 100, "max speed", maxSpeed, "m/s",
          "must be in (0, 100]");
  require(std::isfinite(surfaceBlendTime) && surfaceBlendTime >= 0 && surfaceBlendTime <= 1,
          "surface blend time", surfaceBlendTime, "s", "must be in [0, 1]");
  require(positive(velocityCutoffHz) && velocityCutoffHz <= 0.5 * rateHz, "velocity cut-off",
          velocityCutoffHz, "Hz", "must be > 0 and at most half the loop rate");
}

void HapticSettings::validate() const {
  require(std::isfinite(rateHz) && rateHz >= 100 && rateHz <= 10000, "rate", rateHz, "Hz",
          "must be in [100, 10000]");
  constants.validate();
  limits.validate();
  safety.validate(rateHz);
}

void WorkspaceMap::validate() const {
  require(positive(scale), "workspace scale", scale, "planet m per device m",
          "must be finite and > 0");
  require(origin.allFinite(), "workspace origin", origin.norm(), "m", "must be finite");
  const double orth = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm();
  require(rotation.allFinite() && orth < 1e-6 && rotation.determinant() > 0, "workspace rotation",
          orth, "", "must be a rotation (orthonormal, det +1)");
}

}  // namespace ps::haptics
