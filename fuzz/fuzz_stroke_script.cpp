// libFuzzer: stroke scripts (edit::parseStrokeScript), the text files `demo`/`replay` and the
// tests sculpt from. Any input must parse or be refused with core::InputError; what parses
// writes back (toText) to a script that parses to the same text.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/input_error.hpp"
#include "edit/stroke_script.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::string once;
  try {
    once = ps::edit::parseStrokeScript(text, "fuzz.strokes").toText();
  } catch (const ps::core::InputError&) {
    return 0;
  }
  try {
    if (ps::edit::parseStrokeScript(once, "again.strokes").toText() != once) std::abort();
  } catch (const ps::core::InputError&) {
    std::abort();  // what we wrote must read back
  }
  return 0;
}
