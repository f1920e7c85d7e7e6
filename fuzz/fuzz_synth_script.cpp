// libFuzzer: synth scripts (tracking::parseSynthScript), the JSON scenes `synth` renders. Any
// JSON must parse or be refused with core::InputError; what parses writes back (toJson) to a
// script that parses to the same JSON.
#include "json_round_trip.hpp"
#include "tracking/synth.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ps::fuzz::jsonRoundTrip(
      data, size,
      [](const nlohmann::json& j, const char* name) {
        return ps::tracking::parseSynthScript(j, name);
      },
      [](const ps::tracking::SynthScript& s) { return ps::tracking::toJson(s); });
}
