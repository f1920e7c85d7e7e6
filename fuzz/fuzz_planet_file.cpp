// libFuzzer: the planet-file parser (io::parsePlanet). Any input must either parse or be
// refused with core::InputError; anything else (a crash, a sanitizer report, another
// exception) is a bug.
#include <cstddef>
#include <cstdint>

#include "core/input_error.hpp"
#include "io/planet_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const ps::io::PlanetData d = ps::io::parsePlanet({data, size}, "fuzz.planet");
    // What parses must encode back to the same bytes (float32 files written by us do).
    if (d.encoding == ps::io::HeightEncoding::kFloat32 && d.heightScale == 1.0 &&
        d.heightOffset == 0.0) {
      ps::io::PlanetSaveOptions o;
      o.metadata = d.metadata;
      (void)ps::io::encodePlanet(*d.chart, d.heights, d.rule, o);
    }
  } catch (const ps::core::InputError&) {
  }
  return 0;
}
