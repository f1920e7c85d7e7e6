#include "io/heightmap_import.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <tuple>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/named_values.hpp"
#include "io/nodata_fill.hpp"
#include "io/resample.hpp"

#include "io/import_resample.hpp"
#include "io/import_util.hpp"
#include "io/import_values.hpp"

namespace ps::io {

ImportResult importHeightImage(HeightImage img, const ImportOptions& o, const std::string& name) {
  using namespace import_detail;  // in the function: a unity batch would carry it further
  ImportResult res;
  const int w = img.width, h = img.height;
  const std::size_t n = img.values.size();
  if (w <= 0 || h <= 0 || n != std::size_t(w) * std::size_t(h)) fail(name, "image has no pixels");
  const bool tube = o.chart == ChartKind::kTorus || o.chart == ChartKind::kCylinder;
  // A file that says which surface it maps goes onto that one only (an image of a torus's grid
  // stretched round a sphere would be a silent wrong result).
  const bool declaresTube = img.projection == "torus" || img.projection == "cylinder";
  if ((declaresTube || tube) && !img.projection.empty() &&
      img.projection != core::toString(o.chart)) {
    fail(name, "its metadata says it is a " + img.projection +
                   " heightmap; it cannot be imported onto the " + core::toString(o.chart) +
                   " chart" + (declaresTube ? " (--chart " + img.projection + ")" : ""));
  }
  if (!tube && (o.minorRadius || o.length))
    fail(name, "--minor-radius and --length apply to --chart torus and cylinder");
  const double radius = o.radius           ? *o.radius
                        : img.radiusMetres ? *img.radiusMetres
                                           : kDefaultImportRadius;
  if (tube && !o.radius && !img.radiusMetres)
    fail(name, std::string("a ") + (o.chart == ChartKind::kTorus ? "torus" : "cylinder") +
                   " needs its radius: --radius METRES");
  if ((core::isSphere(o.chart) || tube) && (!std::isfinite(radius) || radius <= 0)) {
    fail(name, "radius " + core::formatNumber(radius, 10) + " m must be positive and finite");
  }
  if (core::isSphere(o.chart)) checkCoversTheGlobe(img, o.chart, name);

  // 1-3. No-data, metres, holes filled.
  const MetresReport metres = toFilledMetres(img, o, radius, name, res.notes);
  const NoDataScan& noData = metres.noData;
  const std::size_t holes = noData.holes;
  const double scale = metres.scale, offset = metres.offset;
  res.noDataPixels = holes;

  // 4. Resample onto the grid.
  const long long side = o.gridSide > 0 ? o.gridSide : defaultGridSide(o.chart, w, h);
  core::GridSize g(5);
  try {
    g = core::GridSize::fromSide(side);
  } catch (const core::InputError& e) {
    fail(name, std::string("--grid: ") + e.what());
  }
  const int m = g.m();
  std::vector<float> heights(g.count());
  nlohmann::json source = {{"file", std::filesystem::path(name).filename().string()},
                           {"kind", img.kind},
                           {"width", w},
                           {"height", h},
                           {"scale", scale},
                           {"offset_m", offset},
                           {"nodata_pixels", holes}};
  if (holes > 0) {
    source["nodata_value"] = noData.nan ? nlohmann::json("nan") : nlohmann::json(*noData.value);
    source["nodata_fill"] = "harmonic";
  }

  if (o.chart == ChartKind::kLatLong) {
    resampleLatLong(img, o, radius, g, name, heights, res, source);
  } else if (core::isSphere(o.chart)) {
    resampleSphere(img, o, radius, g, name, heights, res, source);
  } else if (tube) {
    resampleTubeImage(img, o, radius, g, name, heights, res, source);
  } else {
    resampleFlat(img, o, g, name, heights, res, source);
  }
  if (side != (long long)(std::max(w, h))) {
    res.notes.push_back("resampled " + std::to_string(w) + "x" + std::to_string(h) +
                        " pixels onto the " + g.label() + " grid (" + toString(o.interpolation) +
                        (core::isSphere(o.chart) && (w > averagedSize(o.chart, m).first ||
                                                     h > averagedSize(o.chart, m).second)
                             ? ", area-averaged first"
                             : "") +
                        ")");
  }
  try {
    terrain::Terrain::validateHeights(*res.planet.chart, heights);
  } catch (const core::InputError& e) {
    fail(name, e.what());
  }
  res.planet.heights = std::move(heights);
  res.planet.rule = o.rule;
  res.planet.metadata = {{"generator", "planetsculpt import"}, {"source", source}};
  return res;
}

HeightSamples heightSamples(HeightImage img, const ImportOptions& options,
                            const std::string& name) {
  using namespace import_detail;
  ImportOptions o = options;
  o.chart = ChartKind::kFlat;
  const int w = img.width, h = img.height;
  if (w <= 0 || h <= 0 || img.values.size() != std::size_t(w) * std::size_t(h))
    fail(name, "image has no pixels");
  HeightSamples out;
  const MetresReport metres = toFilledMetres(img, o, 0.0, name, out.notes);
  out.noDataPixels = metres.noData.holes;
  const PixelSpacing spacing = flatSpacing(img, o, name);
  out.dx = spacing.x;
  out.dy = spacing.y;
  out.notes.push_back("flat: " + core::formatNumber(spacing.x, 10) + " x " +
                      core::formatNumber(spacing.y, 10) + " m between pixels, from " +
                      spacing.from + "; the image's own samples, none resampled");
  out.width = w;
  out.height = h;
  out.geo = img.geo;
  out.heights.resize(img.values.size());
  for (int j = 0; j < h; ++j) {  // row 0 of the image is the north edge: j = h - 1
    const float* src = img.values.data() + std::size_t(h - 1 - j) * std::size_t(w);
    std::copy(src, src + w, out.heights.begin() + std::ptrdiff_t(std::size_t(j) * std::size_t(w)));
  }
  for (const float x : out.heights)
    if (!std::isfinite(x) || std::abs(x) > core::FlatChart::kHeightLimit)
      fail(name, "height " + core::formatNumber(x, 10) + " m is not finite or beyond +-" +
                     core::formatNumber(core::FlatChart::kHeightLimit, 10) + " m");
  return out;
}

ImportResult importHeightmap(const std::filesystem::path& path, const ImportOptions& options) {
  return importHeightImage(readHeightImage(path, options.encoding), options, path.string());
}

}  // namespace ps::io
