#include "io/import_resample.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "core/flat_chart.hpp"
#include "core/latlong_chart.hpp"
#include "io/import_util.hpp"

namespace ps::io::import_detail {

namespace {

// An equirectangular image ready to be sampled at any latitude and longitude: area-averaged
// first where it is finer than `maxWidth` x `maxHeight`, then interpolated (o.interpolation).
struct EquirectangularSource {
  std::vector<float> values;
  int width = 0, height = 0;
  double west = -180.0;  // longitude of column 0's western edge, degrees
  Interpolation how = Interpolation::kCubic;

  double at(double latDeg, double lonDeg) const {
    const double x = (lonDeg - west) / 360.0 * width - 0.5;
    const double y = (90.0 - latDeg) / 180.0 * height - 0.5;
    return sampleImage(values, width, height, x, y, true, how);
  }
};

EquirectangularSource equirectangularSource(const HeightImage& img, const ImportOptions& o, int m,
                                            const std::string& name, ImportResult& res,
                                            nlohmann::json& source) {
  const auto [maxWidth, maxHeight] = averagedSize(o.chart, m);
  EquirectangularSource e;
  const int w = img.width, h = img.height;
  if (o.westLongitudeDeg) {
    e.west = *o.westLongitudeDeg;
  } else if (img.column0LongitudeDeg) {
    e.west = *img.column0LongitudeDeg;
  } else if (img.geo && img.geo->geographic) {
    e.west = img.geo->originX;
  }
  if (!std::isfinite(e.west)) fail(name, "western longitude must be finite");
  res.notes.push_back("equirectangular: column 0 starts at " + core::formatNumber(e.west, 10) +
                      " deg longitude, row 0 at 90 deg N");
  source["column0_longitude_deg"] = e.west;
  e.values = img.values;
  e.width = w;
  e.height = h;
  e.how = o.interpolation;
  if (w > maxWidth || h > maxHeight) {
    e.width = std::min(w, maxWidth);
    e.height = std::min(h, maxHeight);
    cv::Mat in(h, w, CV_32F, const_cast<float*>(img.values.data())), out;  // read only
    cv::resize(in, out, cv::Size(e.width, e.height), 0, 0, cv::INTER_AREA);
    e.values.assign(out.begin<float>(), out.end<float>());
  }
  return e;
}

}  // namespace

// The largest equirectangular image a sphere chart's grid samples as it is (a finer one is
// area-averaged down to it first): lat-long m x m, a pixel per cell; the octahedral chart 2m x m,
// about its spacing (its m^2 cells of one area cover the sphere: 2m columns along the equator).
std::pair<int, int> averagedSize(ChartKind chart, int m) {
  return {chart == ChartKind::kLatLong ? m : 2 * m, m};
}

void noteRadius(double radius, const ImportOptions& o, const HeightImage& img, ImportResult& res) {
  res.notes.push_back("radius " + core::formatNumber(radius, 10) + " m, " +
                      (o.radius           ? "as given"
                       : img.radiusMetres ? "from the file"
                                          : "the default (--radius sets it)"));
}

// The equirectangular image onto a lat-long grid: area-averaged first where the image is finer,
// then interpolated (o.interpolation); pole rows one point each.
void resampleLatLong(const HeightImage& img, const ImportOptions& o, double radius,
                     const core::GridSize& g, const std::string& name, std::vector<float>& heights,
                     ImportResult& res, nlohmann::json& source) {
  const int m = g.m();
  const EquirectangularSource e = equirectangularSource(img, o, m, name, res, source);
  for (int gv = 1; gv < m; ++gv) {
    const double lat = 180.0 * gv / m - 90.0;
    for (int gu = 0; gu < m; ++gu) {
      heights[g.index(gu, gv)] = float(e.at(lat, 360.0 * gu / m - 180.0));
    }
    heights[g.index(m, gv)] = heights[g.index(0, gv)];
  }
  // Pole rows: one point each, the mean of the image's samples along the pole's edge.
  for (const int gv : {0, m}) {
    double sum = 0;
    for (int gu = 0; gu < m; ++gu) sum += e.at(gv == 0 ? -90.0 : 90.0, 360.0 * gu / m - 180.0);
    const float pole = float(sum / m);
    for (int gu = 0; gu <= m; ++gu) heights[g.index(gu, gv)] = pole;
  }
  res.planet.chart = std::make_shared<core::LatLongChart>(g, radius);
  noteRadius(radius, o, img, res);
}

// The window along a parallel, in grid spacings: measured on the Mars round trip (rows within 5
// degrees of the poles, rms): point samples 22.5 m, windows of 0.5, 0.75, 1 and 1.5 spacings
// 20.3, 19.9, 20.1 and 22.0 m (the DEM holds about 17.6 m of detail narrower than the spacing).
constexpr double kParallelWindow = 0.75;

// The image's mean along a parallel over `windowDeg` of longitude centred on `lonDeg`: as many
// samples as pixels the window spans (one where it spans less than a pixel), the whole parallel
// at 360 degrees and up.
double alongParallel(const EquirectangularSource& e, double latDeg, double lonDeg,
                     double windowDeg) {
  const double pixelDeg = 360.0 / e.width;
  if (windowDeg <= pixelDeg) return e.at(latDeg, lonDeg);
  const int n = int(std::ceil(std::min(windowDeg, 360.0) / pixelDeg));
  const double step = std::min(windowDeg, 360.0) / n;
  double sum = 0;
  for (int k = 0; k < n; ++k) sum += e.at(latDeg, lonDeg + (k + 0.5 - 0.5 * n) * step);
  return sum / n;
}

// The equirectangular image onto any other sphere chart (the octahedral one): each grid vertex
// samples the image at its own direction's latitude and longitude, averaged along the parallel
// over kParallelWindow of the grid's spacing where the image's pixels there are narrower
// (toward the poles an image's columns crowd: at 89.9 degrees a 1440-column image's pixels are
// 32 m apart on Mars, the 4097^2 grid's vertices 2.9 km; a point sample there aliases the detail
// the grid cannot hold; bench roundtrip, docs/EXPORT.md). The spacing is the chart's mean,
// sqrt(4 pi) / m radians (m^2 cells cover the sphere), one number for every vertex. The grid
// vertices of one point have bit-identical directions (core::Chart::canonical), so they get one
// height.
void resampleSphere(const HeightImage& img, const ImportOptions& o, double radius,
                    const core::GridSize& g, const std::string& name, std::vector<float>& heights,
                    ImportResult& res, nlohmann::json& source) {
  const int m = g.m();
  core::ChartDims dims;
  dims.radius = radius;
  auto chart = core::makeChart(o.chart, g, dims);
  const EquirectangularSource e = equirectangularSource(img, o, m, name, res, source);
  constexpr double kDeg = 180.0 / std::numbers::pi;
  const double windowDeg = kParallelWindow * std::sqrt(4 * std::numbers::pi) / m * kDeg;
#pragma omp parallel for schedule(dynamic, 16)
  for (int gv = 0; gv <= m; ++gv) {
    for (int gu = 0; gu <= m; ++gu) {
      const Eigen::Vector3d d = chart->up(gu, gv);
      const double lat = std::asin(std::clamp(d.z(), -1.0, 1.0)) * kDeg;
      // At a pole every longitude is the pole: 0 there, so its twins agree.
      const double lon = d.x() == 0 && d.y() == 0 ? 0.0 : std::atan2(d.y(), d.x()) * kDeg;
      const double cosLat = std::sqrt(std::max(0.0, 1.0 - d.z() * d.z()));
      const double window = cosLat > windowDeg / 360.0 ? windowDeg / cosLat : 360.0;
      heights[g.index(gu, gv)] = float(alongParallel(e, lat, lon, window));
    }
  }
  res.planet.chart = std::move(chart);
  noteRadius(radius, o, img, res);
}

// A sphere chart takes a global equirectangular image (row 0 at 90 N, 360 x 180 degrees): an
// image whose georeferencing says otherwise (a projected CRS, or a region of the globe) cannot
// be resampled onto it and is refused, rather than stretched round the planet.
void checkCoversTheGlobe(const HeightImage& img, core::ChartShape chart, const std::string& name) {
  if (!img.geo) return;  // no georeferencing: the user says it is global by choosing the chart
  const std::string onto = " cannot be resampled onto the " + core::toString(chart) +
                           " chart, which needs a global equirectangular image (360 x 180 "
                           "degrees); import a regional tile with --chart flat";
  if (!img.geo->geographic)
    fail(name, "its georeferencing is a projected CRS, not degrees: it" + onto);
  const double spanX = img.width * img.geo->pixelScaleX;
  const double spanY = img.height * std::abs(img.geo->pixelScaleY);
  const double tolX = std::abs(img.geo->pixelScaleX), tolY = std::abs(img.geo->pixelScaleY);
  if (std::abs(spanX - 360.0) > tolX || std::abs(spanY - 180.0) > tolY ||
      std::abs(img.geo->originY - 90.0) > tolY) {
    fail(name, "it covers " + core::formatNumber(spanX, 10) + " x " +
                   core::formatNumber(spanY, 10) + " degrees from (" +
                   core::formatNumber(img.geo->originX, 10) + ", " +
                   core::formatNumber(img.geo->originY, 10) + "):" + onto);
  }
}

// Metres between a flat image's pixel centres: the user's, the file's own metadata or its
// GeoTIFF pixel scale.
PixelSpacing flatSpacing(const HeightImage& img, const ImportOptions& o, const std::string& name) {
  PixelSpacing s{1.0, 1.0, "default 1 m per pixel (--spacing sets it)"};
  if (o.spacing) {
    s = {*o.spacing, *o.spacing, "--spacing"};
  } else if (img.pixelSpacingX && img.pixelSpacingY) {
    s = {*img.pixelSpacingX, *img.pixelSpacingY, "the file's own metadata"};
  } else if (img.geo) {
    if (img.geo->geographic) {
      // Degrees on the Earth: metres along a parallel shrink with cos(latitude).
      constexpr double kEarthMean = 6371008.8;
      const double latC = img.geo->originY - 0.5 * img.height * img.geo->pixelScaleY;
      const double k = kEarthMean * std::numbers::pi / 180.0;
      s = {img.geo->pixelScaleX * k * std::cos(latC * std::numbers::pi / 180.0),
           img.geo->pixelScaleY * k,
           "the file's georeferencing in degrees, at latitude " + core::formatNumber(latC, 10) +
               " on the Earth's mean sphere"};
    } else {
      s = {img.geo->pixelScaleX, img.geo->pixelScaleY,
           "the file's georeferencing (taken as metres)"};
    }
  }
  if (!std::isfinite(s.x) || s.x <= 0 || !std::isfinite(s.y) || s.y <= 0) {
    fail(name, "pixel spacing " + core::formatNumber(s.x, 10) + " x " +
                   core::formatNumber(s.y, 10) + " m must be positive and finite");
  }
  return s;
}

// A flat image onto a flat chart's grid (o.interpolation).
void resampleFlat(const HeightImage& img, const ImportOptions& o, const core::GridSize& g,
                  const std::string& name, std::vector<float>& heights, ImportResult& res,
                  nlohmann::json& source) {
  const int w = img.width, h = img.height, m = g.m();
  const std::vector<float>& v = img.values;
  const PixelSpacing spacing = flatSpacing(img, o, name);
  const double sx = spacing.x, sy = spacing.y;
  res.notes.push_back("flat: " + core::formatNumber(sx, 10) + " x " + core::formatNumber(sy, 10) +
                      " m between pixels, from " + spacing.from +
                      "; image row 0 is the north (v = m) edge");
  const double kx = w > 1 ? double(w - 1) / m : 0.0, ky = h > 1 ? double(h - 1) / m : 0.0;
  for (int gv = 0; gv <= m; ++gv) {
    for (int gu = 0; gu <= m; ++gu) {
      heights[g.index(gu, gv)] =
          float(sampleImage(v, w, h, gu * kx, (m - gv) * ky, false, o.interpolation));
    }
  }
  const double dx = w > 1 ? sx * kx : sx, dy = h > 1 ? sy * ky : sy;
  res.planet.chart = std::make_shared<core::FlatChart>(g, dx, dy);
  source["pixel_spacing_m"] = {sx, sy};
}

// An image of a torus's or a cylinder's (u, v) grid (io::resampleTube's layout) onto that chart:
// column x at u = x m / w round the axis; a torus's row y at v = (h - 1 - y) m / h, both ways
// periodic; a cylinder's at v = (h - 1 - y) m / (h - 1), its ends rows 0 and h - 1.
void resampleTubeImage(const HeightImage& img, const ImportOptions& o, double radius,
                       const core::GridSize& g, const std::string& name,
                       std::vector<float>& heights, ImportResult& res, nlohmann::json& source) {
  const bool torus = o.chart == ChartKind::kTorus;
  core::ChartDims dims;
  dims.radius = radius;
  // The user's dimensions, else the file's (a raw export's sidecar names them).
  const std::optional<double> minor = o.minorRadius ? o.minorRadius : img.minorRadiusMetres;
  const std::optional<double> length = o.length ? o.length : img.lengthMetres;
  if (torus) {
    if (!minor) fail(name, "a torus needs its tube's radius: --minor-radius METRES");
    dims.minorRadius = *minor;
  } else {
    if (!length) fail(name, "a cylinder needs its length: --length METRES");
    dims.length = *length;
  }
  try {
    res.planet.chart = core::makeChart(o.chart, g, dims);
  } catch (const core::InputError& e) {
    fail(name, e.what());
  }
  const int w = img.width, h = img.height, m = g.m();
  const std::vector<float>& v = img.values;
  const auto at = [&](int x, int y) {
    x = ((x % w) + w) % w;
    y = torus ? ((y % h) + h) % h : std::clamp(y, 0, h - 1);
    return double(v[std::size_t(y) * std::size_t(w) + std::size_t(x)]);
  };
  const double kx = double(w) / m;
  const double ky = torus ? double(h) / m : double(h - 1) / m;
  for (int gv = 0; gv <= m; ++gv) {
    // The torus's v = m is v = 0 (row h - 1 - h = -1 wraps to h - 1): the twins get one value.
    const double y = torus ? (h - 1) - gv * ky : (m - gv) * ky;
    for (int gu = 0; gu <= m; ++gu)
      heights[g.index(gu, gv)] = float(sampleUnclamped(at, gu * kx, y, o.interpolation));
  }
  res.notes.push_back(
      std::string(torus ? "torus" : "cylinder") +
      ": image column 0 at u = 0, row 0 at the largest v; " +
      (torus ? "both ways periodic"
             : "periodic round the axis, rows 0 and " + std::to_string(h - 1) + " its ends"));
  source["projection"] = torus ? "torus" : "cylinder";
}

}  // namespace ps::io::import_detail
