#pragma once
// The sun as the user gives it: an azimuth and an elevation in degrees, relative to the board the
// planet stands on (azimuth from the board's +x toward +y, elevation above the board), as
// `replay --sun AZ,EL` takes them and the live panel's sliders show them.
#include <Eigen/Core>
#include <string>

namespace ps::render {

struct SunAngles {
  double azimuthDeg = 45;
  double elevationDeg = 35.264389682754654;  // atan(1 / sqrt 2): the sun (1, 1, 1) / sqrt 3
};

// The unit vector toward the sun (board frame: +z up from the board).
Eigen::Vector3d sunDirection(const SunAngles& angles);

// Parses "AZ,EL" (two finite numbers; elevation in -90..90); throws core::InputError naming
// `option` and the text otherwise.
SunAngles parseSunAngles(const std::string& text, const std::string& option = "--sun");

}  // namespace ps::render
