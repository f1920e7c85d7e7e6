// libFuzzer: the heightmap import path for PNG and TIFF bytes: io::decodeHeightImage, then
// io::importHeightImage (no-data, scale, fill, resampling) onto a small grid. The first byte
// picks the chart and the no-data policy; the rest is the image.
#include <cstddef>
#include <cstdint>

#include "core/input_error.hpp"
#include "io/heightmap_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t mode = data[0];
  try {
    // A 2^28-pixel image is legal and needs gigabytes: libFuzzer's memory limit is not the point
    // here, so the harness asks for at most 2^20 pixels (the same refusal path, earlier).
    ps::io::HeightImage img =
        ps::io::decodeHeightImage({data + 1, size - 1}, "fuzz.img", std::uint64_t(1) << 20);
    if (img.pixelCount() > (1u << 18)) return 0;  // decoding was the point; keep runs fast
    ps::io::ImportOptions o;
    o.chart = (mode & 1) ? ps::io::ChartKind::kFlat : ps::io::ChartKind::kLatLong;
    o.noData = (mode & 2) ? ps::io::NoDataPolicy::kRefuse : ps::io::NoDataPolicy::kFill;
    o.gridSide = 33;
    if (mode & 4) o.scale = 0.5;
    (void)ps::io::importHeightImage(std::move(img), o, "fuzz.img");
  } catch (const ps::core::InputError&) {
  }
  return 0;
}
