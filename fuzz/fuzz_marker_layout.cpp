// libFuzzer: marker layout files (tracking::parseMarkerLayout): the planet board and the tool
// solids in markers/*.json, and any a user makes. Any JSON must parse or be refused with
// core::InputError; what parses writes back (toJson) to a layout that parses to the same JSON.
#include "json_round_trip.hpp"
#include "tracking/marker_layout.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ps::fuzz::jsonRoundTrip(
      data, size,
      [](const nlohmann::json& j, const char* name) {
        return ps::tracking::parseMarkerLayout(j, name);
      },
      [](const ps::tracking::MarkerLayout& l) { return ps::tracking::toJson(l); });
}
