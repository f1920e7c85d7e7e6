// libFuzzer: the raw-heightmap sidecar JSON (io::parseRawSidecar) and the raw decoder it
// drives. Input: the sidecar text, then (after the first NUL byte, if any) the raw data.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "core/input_error.hpp"
#include "io/height_image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto* nul = static_cast<const std::uint8_t*>(std::memchr(data, 0, size));
  const std::size_t jsonBytes = nul ? std::size_t(nul - data) : size;
  try {
    const ps::io::RawSidecar s = ps::io::parseRawSidecar(
        std::string_view(reinterpret_cast<const char*>(data), jsonBytes), "fuzz.raw.json");
    if (nul) (void)ps::io::decodeRaw({nul + 1, size - jsonBytes - 1}, s, "fuzz.raw");
  } catch (const ps::core::InputError&) {
  }
  return 0;
}
