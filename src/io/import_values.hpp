#pragma once
// A heightmap's stored values -> metres, in place, for `planetsculpt import`: which pixels hold
// no data, the scale and offset, radii -> heights on a sphere, and the holes filled.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "io/heightmap_import.hpp"

namespace ps::io::import_detail {

// Which pixels hold no data (declared by the file, e.g. GDAL_NODATA or a sidecar, or by the
// user); any other non-finite pixel, every pixel missing, or holes under --nodata refuse are
// refused naming the file.
struct NoDataScan {
  std::optional<double> value;
  std::string source;
  bool nan = false;  // NaN marks no data
  std::vector<std::uint8_t> hole;
  std::size_t holes = 0;
};

struct MetresReport {
  NoDataScan noData;
  double scale = 1, offset = 0;
};

// The image's values -> metres in place, its no-data pixels filled: 1. which pixels hold no data,
// 2. stored values -> metres (radii -> heights on a sphere), 3. the holes filled.
MetresReport toFilledMetres(HeightImage& img, const ImportOptions& o, double radius,
                            const std::string& name, std::vector<std::string>& notes);

}  // namespace ps::io::import_detail
