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

namespace ps::io {

namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

std::string num(double x) {
  std::ostringstream os;
  os.precision(10);
  os << x;
  return os.str();
}

int levelFor(long long cells) {
  int n = core::GridSize::kMinLevel;
  while (n < 13 && (1LL << n) < cells) ++n;
  return n;
}

// A sample of image values `v` (w x h) at pixel coordinates (x, y), pixel centres at integers.
double sampleImage(const std::vector<float>& v, int w, int h, double x, double y, bool wrapX,
                   Interpolation how) {
  const auto at = [&](int xi, int yi) {
    return double(v[std::size_t(yi) * std::size_t(w) + std::size_t(xi)]);
  };
  return sample(at, w, h, x, y, wrapX, how);
}

}  // namespace

constexpr core::NameTable<Interpolation, 2> kInterpolations{
    "interpolation", {{{Interpolation::kCubic, "cubic"}, {Interpolation::kBilinear, "bilinear"}}}};

std::string toString(Interpolation i) {
  return kInterpolations.nameOf(i);
}

Interpolation interpolationFromString(const std::string& s) {
  return kInterpolations.parse(s);
}

ChartKind chartKindFromString(const std::string& s) {
  return core::chartShapeFromString(s);
}

NoDataPolicy noDataPolicyFromString(const std::string& s) {
  constexpr core::NameTable<NoDataPolicy, 2> kPolicies{
      "no-data policy", {{{NoDataPolicy::kFill, "fill"}, {NoDataPolicy::kRefuse, "refuse"}}}};
  return kPolicies.parse(s);
}

double noDataValueFromString(const std::string& s) {
  if (s == "nan" || s == "NaN" || s == "NAN") return std::numeric_limits<double>::quiet_NaN();
  std::size_t used = 0;
  double x = 0;
  try {
    x = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (s.empty() || used != s.size() || !std::isfinite(x)) {
    throw core::InputError("--nodata-value '" + s + "' is not a finite number or nan");
  }
  return x;
}

long long defaultGridSide(ChartKind chart, int width, int height) {
  // latlong: m cells span 360 deg of longitude and 180 deg of latitude; the grid is twice as fine
  // as the image both ways, so that a round trip through it (cubic both ways) comes back within
  // the image's own precision (docs/EXPORT.md: Mars at 1440x720, 4097^2: rms 1.85 m; at 2049^2,
  // as fine as the image along the equator: 13.3 m). The octahedral chart takes the same side:
  // at 2049^2 its error per area is 11.4 m against lat-long's 15.5, at 4097^2 2.6 against 2.2
  // (docs/CHARTS.md). flat: the image's own samples.
  // torus and cylinder: the image's own columns (and a torus's rows) as cells, so that an image
  // of the grid's own size (io::resampleTube) comes back onto the same grid.
  const long long cells = core::isSphere(chart) ? std::max<long long>(2LL * width, 4LL * height)
                          : chart == ChartKind::kTorus    ? std::max<long long>(width, height)
                          : chart == ChartKind::kCylinder ? std::max<long long>(width, height - 1LL)
                                                          : std::max<long long>(width, height) - 1;
  return (1LL << levelFor(cells)) + 1;
}

namespace {

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
    fail(name, "every pixel is no-data (value " + num(*r.value) + ", " + r.source + ")");
  if (r.holes > 0 && o.noData == NoDataPolicy::kRefuse) {
    fail(name, std::to_string(r.holes) + " pixels are no-data (value " + num(*r.value) + ", " +
                   r.source +
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
    notes.push_back("heights: value x " + num(scale) + " + " + num(offset) + " m");
  } else if (img.value0Metres && img.value65535Metres && img.kind == "16-bit grey PNG") {
    offset = *img.value0Metres;
    scale = (*img.value65535Metres - *img.value0Metres) / 65535.0;
    notes.push_back("heights: the PNG's PlanetSculpt text chunks map 0 to " + num(offset) +
                    " m and 65535 to " + num(*img.value65535Metres) + " m");
  } else if (img.fileScale || img.fileOffset) {
    scale = img.fileScale.value_or(1.0);
    offset = img.fileOffset.value_or(0.0);
    notes.push_back("heights: value x " + num(scale) + " + " + num(offset) +
                    " m, the file's own scale and offset (--scale and --offset override them)");
  } else {
    notes.push_back(
        "heights: the stored values are taken as metres (scale 1, offset 0); "
        "--scale and --offset map them otherwise");
  }
  if (!std::isfinite(scale) || scale == 0 || !std::isfinite(offset)) {
    fail(name, "height scale " + num(scale) + " and offset " + num(offset) +
                   " must be finite, scale non-zero");
  }
  std::vector<float>& v = img.values;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (hole[i]) continue;
    const double m = double(v[i]) * scale + offset;
    if (!std::isfinite(float(m))) {
      fail(name, "pixel (x=" + std::to_string(i % std::size_t(w)) +
                     ", y=" + std::to_string(i / std::size_t(w)) + ") becomes " + num(m) +
                     " m after scale and offset, beyond float range");
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
  notes.push_back("heights: the values are distances from the centre (median " + num(*mid) +
                  " m), so the radius " + num(radius) + " m is subtracted");
}

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

// The largest equirectangular image a sphere chart's grid samples as it is (a finer one is
// area-averaged down to it first): lat-long m x m, a pixel per cell; the octahedral chart 2m x m,
// about its spacing (its m^2 cells of one area cover the sphere: 2m columns along the equator).
std::pair<int, int> averagedSize(ChartKind chart, int m) {
  return {chart == ChartKind::kLatLong ? m : 2 * m, m};
}

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
  res.notes.push_back("equirectangular: column 0 starts at " + num(e.west) +
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

void noteRadius(double radius, const ImportOptions& o, const HeightImage& img, ImportResult& res) {
  res.notes.push_back("radius " + num(radius) + " m, " +
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

// The equirectangular image onto any other sphere chart (the octahedral one): each grid vertex
// samples the image at its own direction's latitude and longitude. The grid vertices of one
// point have bit-identical directions (core::Chart::canonical), so they get one height.
void resampleSphere(const HeightImage& img, const ImportOptions& o, double radius,
                    const core::GridSize& g, const std::string& name, std::vector<float>& heights,
                    ImportResult& res, nlohmann::json& source) {
  const int m = g.m();
  core::ChartDims dims;
  dims.radius = radius;
  auto chart = core::makeChart(o.chart, g, dims);
  const EquirectangularSource e = equirectangularSource(img, o, m, name, res, source);
  constexpr double kDeg = 180.0 / std::numbers::pi;
#pragma omp parallel for schedule(static)
  for (int gv = 0; gv <= m; ++gv) {
    for (int gu = 0; gu <= m; ++gu) {
      const Eigen::Vector3d d = chart->up(gu, gv);
      const double lat = std::asin(std::clamp(d.z(), -1.0, 1.0)) * kDeg;
      // At a pole every longitude is the pole: 0 there, so its twins agree.
      const double lon = d.x() == 0 && d.y() == 0 ? 0.0 : std::atan2(d.y(), d.x()) * kDeg;
      heights[g.index(gu, gv)] = float(e.at(lat, lon));
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
    fail(name, "it covers " + num(spanX) + " x " + num(spanY) + " degrees from (" +
                   num(img.geo->originX) + ", " + num(img.geo->originY) + "):" + onto);
  }
}

struct MetresReport {
  NoDataScan noData;
  double scale = 1, offset = 0;
};

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
    notes.push_back(
        std::to_string(r.noData.holes) + " no-data pixels (value " + num(*r.noData.value) + ", " +
        r.noData.source + ") filled by harmonic interpolation from the surrounding heights (" +
        std::to_string(fr.sweeps) + " relaxation sweeps); none of them became a height as stored");
  }
  return r;
}

struct PixelSpacing {
  double x = 1.0, y = 1.0;
  std::string from;
};

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
           "the file's georeferencing in degrees, at latitude " + num(latC) +
               " on the Earth's mean sphere"};
    } else {
      s = {img.geo->pixelScaleX, img.geo->pixelScaleY,
           "the file's georeferencing (taken as metres)"};
    }
  }
  if (!std::isfinite(s.x) || s.x <= 0 || !std::isfinite(s.y) || s.y <= 0) {
    fail(name, "pixel spacing " + num(s.x) + " x " + num(s.y) + " m must be positive and finite");
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
  res.notes.push_back("flat: " + num(sx) + " x " + num(sy) + " m between pixels, from " +
                      spacing.from + "; image row 0 is the north (v = m) edge");
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

}  // namespace

ImportResult importHeightImage(HeightImage img, const ImportOptions& o, const std::string& name) {
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
    fail(name, "radius " + num(radius) + " m must be positive and finite");
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
  out.notes.push_back("flat: " + num(spacing.x) + " x " + num(spacing.y) +
                      " m between pixels, from " + spacing.from +
                      "; the image's own samples, none resampled");
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
      fail(name, "height " + num(x) + " m is not finite or beyond +-" +
                     num(core::FlatChart::kHeightLimit) + " m");
  return out;
}

ImportResult importHeightmap(const std::filesystem::path& path, const ImportOptions& options) {
  return importHeightImage(readHeightImage(path, options.encoding), options, path.string());
}

}  // namespace ps::io
