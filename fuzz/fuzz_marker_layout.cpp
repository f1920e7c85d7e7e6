// libFuzzer: marker layout files (tracking::parseMarkerLayout): the planet board and the tool
// solids in markers/*.json, and any a user makes. Any JSON must parse or be refused with
// core::InputError; what parses writes back (toJson) to a layout that parses to the same JSON.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "core/input_error.hpp"
#include "tracking/marker_layout.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, false);
  if (j.is_discarded()) return 0;
  nlohmann::json once;
  try {
    once = ps::tracking::toJson(ps::tracking::parseMarkerLayout(j, "fuzz.json"));
  } catch (const ps::core::InputError&) {
    return 0;
  }
  try {
    if (ps::tracking::toJson(ps::tracking::parseMarkerLayout(once, "again.json")) != once)
      std::abort();
  } catch (const ps::core::InputError&) {
    std::abort();
  }
  return 0;
}
