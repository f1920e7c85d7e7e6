#include "io/import_values.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/chart_factory.hpp"
#include "io/import_util.hpp"
#include "io/nodata_fill.hpp"

namespace ps::io::import_detail {

namespace {

NoDataScan scanNoData(const HeightImage& img, const ImportOptions& o, const std::string& name) {
  const int w = img.width;
  const std::size_t n = img.values.size();
  NoDataScan r;
  r.value = img.noData;
  r.source = img.noDataSource;
  if (o.noDataValue) {
    r.value = o.noDataValue;
    r.source = "--nodata-value";
  }
  r.nan = r.value && std::isnan(*r.value);
  const float noDataF = r.value && !r.nan ? float(*r.value) : 0.0f;
  r.hole.assign(n, 0);
  std::size_t nonFinite = 0, firstBad = n;
  for (std::size_t i = 0; i < n; ++i) {
    const float x = img.values[i];
    if (r.value && (r.nan ? std::isnan(x) : x == noDataF)) {
      r.hole[i] = 1;
      ++r.holes;
    } else if (!std::isfinite(x)) {
      if (firstBad == n) firstBad = i;
      ++nonFinite;
    }
  }
  if (nonFinite > 0) {
    const float x = img.values[firstBad];
    fail(name,
         "pixel (x=" + std::to_string(firstBad % std::size_t(w)) +
             ", y=" + std::to_string(firstBad / std::size_t(w)) + ") is " +
             (std::isnan(x) ? "NaN" : "infinite") +
             (nonFinite > 1 ? " (and " + std::to_string(nonFinite - 1) + " more non-finite pixels)"
                            : "") +
             ": a height must be finite; if these mark missing data, say so with "
             "--nodata-value nan");
  }
  if (r.holes == n)
    fail(name, "every pixel is no-data (value " + core::formatNumber(*r.value, 10) + ", " +
                   r.source + ")");
  if (r.holes > 0 && o.noData == NoDataPolicy::kRefuse) {
    fail(name, std::to_string(r.holes) + " pixels are no-data (value " +
                   core::formatNumber(*r.value, 10) + ", " + r.source +
                   "); refused as asked (--nodata refuse); --nodata fill fills them from their "
                   "surroundings");
  }
  return r;
}

// Stored values -> metres, in place (holes left alone): the user's scale and offset, a
// PlanetSculpt PNG's own text chunks, or metres as stored. Returns {scale, offset}.
std::pair<double, double> toMetres(HeightImage& img, const ImportOptions& o,
                                   const std::vector<std::uint8_t>& hole, const std::string& name,
                                   std::vector<std::string>& notes) {
  const int w = img.width;
  double scale = 1.0, offset = 0.0;
  if (o.scale || o.offset) {
    scale = o.scale.value_or(1.0);
    offset = o.offset.value_or(0.0);
    notes.push_back("heights: value x " + core::formatNumber(scale, 10) + " + " +
                    core::formatNumber(offset, 10) + " m");
  } else if (img.value0Metres && img.value65535Metres && img.kind == "16-bit grey PNG") {
    offset = *img.value0Metres;
    scale = (*img.value65535Metres - *img.value0Metres) / 65535.0;
    notes.push_back("heights: the PNG's PlanetSculpt text chunks map 0 to " +
                    core::formatNumber(offset, 10) + " m and 65535 to " +
                    core::formatNumber(*img.value65535Metres, 10) + " m");
  } else if (img.fileScale || img.fileOffset) {
    scale = img.fileScale.value_or(1.0);
    offset = img.fileOffset.value_or(0.0);
    notes.push_back("heights: value x " + core::formatNumber(scale, 10) + " + " +
                    core::formatNumber(offset, 10) +
                    " m, the file's own scale and offset (--scale and --offset override them)");
  } else {
    notes.push_back(
        "heights: the stored values are taken as metres (scale 1, offset 0); "
        "--scale and --offset map them otherwise");
  }
  if (!std::isfinite(scale) || scale == 0 || !std::isfinite(offset)) {
    fail(name, "height scale " + core::formatNumber(scale, 10) + " and offset " +
                   core::formatNumber(offset, 10) + " must be finite, scale non-zero");
  }
  std::vector<float>& v = img.values;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (hole[i]) continue;
    const double m = double(v[i]) * scale + offset;
    if (!std::isfinite(float(m))) {
      fail(name, "pixel (x=" + std::to_string(i % std::size_t(w)) +
                     ", y=" + std::to_string(i / std::size_t(w)) + ") becomes " +
                     core::formatNumber(m, 10) + " m after scale and offset, beyond float range");
    }
    v[i] = float(m);
  }
  return {scale, offset};
}

// Planetary radius products (e.g. LOLA's, whose label's offset is the body's radius) hold each
// point's distance from the centre, not its height: when the median value is over half the
// radius, the radius is subtracted (and the user told).
void radiiToHeights(std::vector<float>& v, const std::vector<std::uint8_t>& hole, double radius,
                    std::vector<std::string>& notes) {
  std::vector<float> sample;
  const std::size_t step = std::max<std::size_t>(1, v.size() / 100000);
  for (std::size_t i = 0; i < v.size(); i += step)
    if (hole.empty() || !hole[i]) sample.push_back(v[i]);
  if (sample.empty()) return;
  auto mid = sample.begin() + std::ptrdiff_t(sample.size() / 2);
  std::nth_element(sample.begin(), mid, sample.end());
  if (!(double(*mid) > 0.5 * radius)) return;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (hole.empty() || !hole[i]) v[i] = float(double(v[i]) - radius);
  notes.push_back("heights: the values are distances from the centre (median " +
                  core::formatNumber(*mid, 10) + " m), so the radius " +
                  core::formatNumber(radius, 10) + " m is subtracted");
}

}  // namespace

// The image's values -> metres in place, its no-data pixels filled: 1. which pixels hold no data,
// 2. stored values -> metres (radii -> heights on a sphere), 3. the holes filled.
MetresReport toFilledMetres(HeightImage& img, const ImportOptions& o, double radius,
                            const std::string& name, std::vector<std::string>& notes) {
  MetresReport r;
  r.noData = scanNoData(img, o, name);
  std::tie(r.scale, r.offset) = toMetres(img, o, r.noData.hole, name, notes);
  std::vector<float>& v = img.values;
  const bool sphere = core::isSphere(o.chart);
  if (sphere) radiiToHeights(v, r.noData.hole, radius, notes);
  if (r.noData.holes > 0) {
    const FillReport fr = fillHoles(v, img.width, img.height, r.noData.hole, sphere);
    notes.push_back(std::to_string(r.noData.holes) + " no-data pixels (value " +
                    core::formatNumber(*r.noData.value, 10) + ", " + r.noData.source +
                    ") filled by harmonic interpolation from the surrounding heights (" +
                    std::to_string(fr.sweeps) +
                    " relaxation sweeps); none of them became a height as stored");
  }
  return r;
}

}  // namespace ps::io::import_detail
