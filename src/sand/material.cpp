#include "sand/material.hpp"

#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::sand {

namespace {

void checkAngle(const char* what, double deg) {
  if (!std::isfinite(deg) || !(deg > 0.0) || !(deg < 90.0)) {
    throw core::InputError(std::string(what) + " = " + core::exactNumber(deg) +
                           " deg must be inside (0, 90) degrees");
  }
}

void checkNonNegative(const char* what, double x) {
  if (!std::isfinite(x) || x < 0.0) {
    throw core::InputError(std::string(what) + " = " + core::exactNumber(x) +
                           " must be finite and >= 0");
  }
}

void checkTolerance(const char* what, double x) {
  if (!std::isfinite(x) || x < 1e-9 || x > 0.1) {
    throw core::InputError(std::string(what) + " = " + core::exactNumber(x) +
                           " must be in [1e-9, 0.1]");
  }
}

}  // namespace

void Material::validate() const {
  checkAngle("talus angle", talusDeg);
  if (!std::isfinite(erosionRate) || !(erosionRate > 0.0) || erosionRate > 1.0) {
    throw core::InputError("erosion rate c = " + core::exactNumber(erosionRate) +
                           " must be in (0, 1] (c > 1 overshoots; see docs/SAND.md)");
  }
  checkTolerance("talus tolerance", talusTolerance);
  checkNonNegative("diffusion D", diffusion);
  if (diffusion > 1e6) {
    throw core::InputError("diffusion D = " + core::exactNumber(diffusion) +
                           " exceeds the usable 1e6");
  }
  checkNonNegative("friction inverse zeta^-1", frictionInverse);
  checkAngle("angle of repose alpha", reposeDeg);
  checkTolerance("repose tolerance", reposeTolerance);
  checkNonNegative("cohesion", cohesion);
}

double Material::tanTalus() const {
  return std::tan(talusDeg * std::numbers::pi / 180.0);
}

Material Material::sand() {
  Material m;
  m.name = "sand";
  m.talusDeg = 30.0;  // paper 004, section 3.2
  m.diffusion = 1.0;  // paper 002, Figure 4: D = 1, zeta^-1 = 4e-4, alpha = pi/4
  m.frictionInverse = 4.0e-4;
  m.reposeDeg = 45.0;
  m.cohesion = 0.0;
  return m;
}

Material Material::mud() {
  Material m;
  m.name = "mud";
  // Paper 002, Figure 4: D = 0.25, zeta^-1 = 6e-4, alpha printed "25 pi" = 2 pi / 5 (72 deg);
  // see docs/SAND.md for why we read it that way. The same angle serves as mud's talus.
  m.diffusion = 0.25;
  m.frictionInverse = 6.0e-4;
  m.reposeDeg = 72.0;
  m.talusDeg = 72.0;
  // Rankine's critical height of a vertical cut, H_c = 4 c_u / gamma, for a soft clay
  // (c_u = 10 kPa, gamma = 18 kN/m^3): 2.2 m.
  m.cohesion = 2.2;
  return m;
}

Material Material::pebbles() {
  Material m;
  m.name = "pebbles";
  // Paper 002, Figure 4: D = 0.9, zeta^-1 = 3e-4, alpha = pi/3; the same angle as talus.
  m.diffusion = 0.9;
  m.frictionInverse = 3.0e-4;
  m.reposeDeg = 60.0;
  m.talusDeg = 60.0;
  m.cohesion = 0.0;
  return m;
}

Material Material::preset(const std::string& name) {
  if (name == "sand") return sand();
  if (name == "mud") return mud();
  if (name == "pebbles") return pebbles();
  std::string names;
  for (const std::string& n : presetNames()) names += (names.empty() ? "" : ", ") + n;
  throw core::InputError("material '" + name + "' is not one of " + names);
}

const std::vector<std::string>& Material::presetNames() {
  static const std::vector<std::string> names = {"sand", "mud", "pebbles"};
  return names;
}

}  // namespace ps::sand
