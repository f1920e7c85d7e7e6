#include "render/sun.hpp"

#include <cmath>
#include <cstdlib>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::render {

Eigen::Vector3d sunDirection(const SunAngles& a) {
  const double deg = std::numbers::pi / 180;
  const double az = a.azimuthDeg * deg, el = a.elevationDeg * deg;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

namespace {

// The whole of `text` as one finite number, or false.
bool number(const std::string& text, double& value) {
  if (text.empty() || text.find_first_not_of(" \t") == std::string::npos) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  while (*end == ' ' || *end == '\t') ++end;
  return *end == '\0' && std::isfinite(value);
}

}  // namespace

SunAngles parseSunAngles(const std::string& text, const std::string& option) {
  const auto bad = [&](const std::string& why) {
    return core::InputError(option + " '" + text + "': " + why);
  };
  const auto comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos)
    throw bad("needs two numbers AZ,EL (degrees: azimuth on the board, elevation above it)");
  SunAngles a;
  if (!number(text.substr(0, comma), a.azimuthDeg) ||
      !number(text.substr(comma + 1), a.elevationDeg))
    throw bad("needs two finite numbers AZ,EL (degrees)");
  if (a.elevationDeg < -90 || a.elevationDeg > 90)
    throw bad("the elevation " + core::exactNumber(a.elevationDeg) + " is not in -90..90 degrees");
  return a;
}

}  // namespace ps::render
