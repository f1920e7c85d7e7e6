// libFuzzer: camera calibration files (tracking::parseCalibration, the reader loadCalibration
// uses after opening the file), through OpenCV's FileStorage (YAML, XML, JSON). Any input must
// give a valid calibration or be refused with core::InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/input_error.hpp"
#include "tracking/calibration.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const ps::tracking::CameraCalibration c = ps::tracking::parseCalibration(text, "fuzz.yml");
    c.validate();  // the reader validated it: a throw here is a bug
  } catch (const ps::core::InputError&) {
  }
  return 0;
}
