#include "io/heightmap_export.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/chart_factory.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "io/atomic_file.hpp"
#include "io/gdal_raster.hpp"
#include "io/png_codec.hpp"

namespace ps::io {

namespace {

// Any sphere chart other than lat-long: each pixel's direction goes through the chart's inverse
// to grid coordinates, interpolated there (the stencil reads across the sides the chart glues:
// core::Chart::continued).
Raster resampleSphereChart(const terrain::Terrain& t, Raster r, Interpolation how) {
  const core::Chart& chart = t.chart();
  const int m = t.grid().m(), width = r.width, height = r.height;
  const auto at = [&](int u, int v) {
    const core::GridPoint c = chart.continued(u, v);
    return double(t.height(c.u, c.v));
  };
#pragma omp parallel for schedule(static)
  for (int y = 0; y < height; ++y) {
    const double lat = std::numbers::pi * (0.5 - (y + 0.5) / height);
    for (int x = 0; x < width; ++x) {
      const double lon = std::numbers::pi * (2.0 * (x + 0.5) / width - 1.0);
      const Eigen::Vector3d d(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                              std::sin(lat));
      const Eigen::Vector2d uv = *chart.inverse(chart.sphereRadius() * d);
      // The interpolation stencil reads up to two steps beyond the grid: continued() maps
      // them back.
      const double u = std::clamp(uv.x(), 0.0, double(m)), v = std::clamp(uv.y(), 0.0, double(m));
      r.metres[std::size_t(y) * std::size_t(width) + std::size_t(x)] =
          float(sampleUnclamped(at, u, v, how));
    }
  }
  return r;
}

}  // namespace

Raster resampleEquirectangular(const terrain::Terrain& t, int width, int height,
                               Interpolation how) {
  if (width <= 0 || height <= 0 || double(width) * height > 4e8) {
    throw std::invalid_argument("raster size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is empty or too large");
  }
  const core::Chart& chart = t.chart();
  if (!core::isSphere(core::shapeOf(chart))) {
    throw std::invalid_argument("an equirectangular raster needs a spherical planet, not a '" +
                                chart.name() + "' chart");
  }
  Raster r{width, height, std::vector<float>(std::size_t(width) * std::size_t(height))};
  r.radiusMetres = chart.sphereRadius();
  if (!chart.hasPoleRows()) return resampleSphereChart(t, std::move(r), how);
  const int m = t.grid().m();
  // Grid vertex (u, v) is sample (u, v): u wraps round the m columns (u = m is u = 0), v clamps
  // at the poles.
  const auto at = [&](int u, int v) { return double(t.height(u, v)); };
#pragma omp parallel for schedule(static)
  for (int y = 0; y < height; ++y) {
    const double v = (1.0 - (y + 0.5) / height) * m;
    for (int x = 0; x < width; ++x) {
      const double u = (x + 0.5) / width * m;
      r.metres[std::size_t(y) * std::size_t(width) + std::size_t(x)] =
          float(sample(at, m, m + 1, u, v, true, how));
    }
  }
  return r;
}

namespace {

std::string projectionText(const Raster& r) {
  if (r.layout == Raster::Layout::kFlat) return "flat, pixel is point, row 0 at v = m";
  if (r.layout == Raster::Layout::kTorus) return "torus, (u, v) grid, both ways periodic";
  if (r.layout == Raster::Layout::kCylinder)
    return "cylinder, (u, v) grid, u periodic, rows 0 and last its ends";
  return "equirectangular, row 0 north, column 0 at -180 deg";
}

void checkRaster(const Raster& r, const std::filesystem::path& path) {
  if (r.width <= 0 || r.height <= 0 ||
      r.metres.size() != std::size_t(r.width) * std::size_t(r.height)) {
    throw std::invalid_argument("raster for " + path.string() + " is empty or inconsistent");
  }
}

// The sidecar JSON common to every heightmap format.
nlohmann::json describe(const Raster& r, const std::filesystem::path& path,
                        const std::string& format) {
  nlohmann::json j = {{"file", path.filename().string()},
                      {"format", format},
                      {"width", r.width},
                      {"height", r.height},
                      {"units", "m"}};
  if (r.layout == Raster::Layout::kFlat) {
    j["projection"] = "flat";
    j["pixel_is"] = "point";
    j["row0"] = "v = m (north)";
    j["pixel_spacing_m"] = {r.pixelWidthM, r.pixelHeightM};
  } else if (r.layout == Raster::Layout::kTorus || r.layout == Raster::Layout::kCylinder) {
    const bool torus = r.layout == Raster::Layout::kTorus;
    j["projection"] = torus ? "torus" : "cylinder";
    j["column0"] = "u = 0";
    j["row0"] = torus ? "v = m - m / height" : "v = m";
    j["radius_m"] = r.radiusMetres;
    if (torus) {
      j["minor_radius_m"] = r.minorRadiusM;
    } else {
      j["length_m"] = r.lengthM;
    }
  } else {
    j["projection"] = "equirectangular";
    j["pixel_is"] = "area";
    j["row0"] = "north";
    j["column0_longitude_deg"] = -180.0;
    if (r.radiusMetres > 0) j["radius_m"] = r.radiusMetres;
  }
  return j;
}

void writeSidecar(const nlohmann::json& side, const std::filesystem::path& path) {
  auto sidecar = path;
  sidecar += ".json";
  writeAtomically(sidecar, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp);
    f << side.dump(2) << "\n";
    f.close();
    if (!f) throw std::runtime_error("cannot write " + sidecar.string());
  });
}

}  // namespace

Raster resampleFlat(const terrain::Terrain& t, int width, int height, Interpolation how) {
  const auto* flat = dynamic_cast<const core::FlatChart*>(&t.chart());
  if (!flat)
    throw std::invalid_argument("resampleFlat needs a flat chart, not '" + t.chart().name() + "'");
  if (width <= 0 || height <= 0 || double(width) * height > 4e8) {
    throw std::invalid_argument("raster size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is empty or too large");
  }
  Raster r{width, height, std::vector<float>(std::size_t(width) * std::size_t(height))};
  r.layout = Raster::Layout::kFlat;
  const int m = t.grid().m();
  const double kx = width > 1 ? double(m) / (width - 1) : 0.0,
               ky = height > 1 ? double(m) / (height - 1) : 0.0;
  r.pixelWidthM = width > 1 ? flat->dx() * kx : flat->dx() * m;
  r.pixelHeightM = height > 1 ? flat->dy() * ky : flat->dy() * m;
  const auto at = [&](int u, int v) { return double(t.height(u, v)); };
#pragma omp parallel for schedule(static)
  for (int y = 0; y < height; ++y) {
    const double v = m - y * ky;
    for (int x = 0; x < width; ++x)
      r.metres[std::size_t(y) * std::size_t(width) + std::size_t(x)] =
          float(sample(at, m + 1, m + 1, x * kx, v, false, how));
  }
  return r;
}

Raster resampleTube(const terrain::Terrain& t, int width, int height, Interpolation how) {
  const core::ChartShape shape = core::shapeOf(t.chart());
  const bool torus = shape == core::ChartShape::kTorus;
  if (!torus && shape != core::ChartShape::kCylinder)
    throw std::invalid_argument("resampleTube needs a torus or a cylinder, not '" +
                                t.chart().name() + "'");
  if (width <= 0 || height <= 0 || double(width) * height > 4e8) {
    throw std::invalid_argument("raster size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is empty or too large");
  }
  Raster r{width, height, std::vector<float>(std::size_t(width) * std::size_t(height))};
  r.layout = torus ? Raster::Layout::kTorus : Raster::Layout::kCylinder;
  const core::ChartDims dims = core::dimsOf(t.chart());
  r.radiusMetres = dims.radius;
  r.minorRadiusM = dims.minorRadius;
  r.lengthM = dims.length;
  const int m = t.grid().m();
  // u wraps round the m columns (u = m is u = 0); a torus's v likewise, a cylinder's clamps.
  const auto at = [&](int u, int v) {
    u = ((u % m) + m) % m;
    v = torus ? ((v % m) + m) % m : std::clamp(v, 0, m);
    return double(t.height(u, v));
  };
  const double ku = double(m) / width;
  const double kv = torus ? double(m) / height : height > 1 ? double(m) / (height - 1) : 0.0;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < height; ++y) {
    const double v = (height - 1 - y) * kv;
    for (int x = 0; x < width; ++x)
      r.metres[std::size_t(y) * std::size_t(width) + std::size_t(x)] =
          float(sampleUnclamped(at, x * ku, v, how));
  }
  return r;
}

void writeHeightPng16(const Raster& raster, const std::filesystem::path& path) {
  checkRaster(raster, path);
  const auto [lo, hi] = std::minmax_element(raster.metres.begin(), raster.metres.end());
  const double minM = *lo, maxM = *hi;
  const double span = std::max(maxM - minM, 1e-6);
  cv::Mat img(raster.height, raster.width, CV_16UC1);
  for (int y = 0; y < raster.height; ++y) {
    auto* row = img.ptr<std::uint16_t>(y);
    for (int x = 0; x < raster.width; ++x) {
      const double h = raster.metres[std::size_t(y) * std::size_t(raster.width) + std::size_t(x)];
      row[x] = std::uint16_t(std::lround(std::clamp((h - minM) / span, 0.0, 1.0) * 65535.0));
    }
  }
  PngText text = {{"planetsculpt:min_m", core::exactNumber(minM)},
                  {"planetsculpt:max_m", core::exactNumber(maxM)},
                  {"planetsculpt:projection", projectionText(raster)}};
  if (raster.layout == Raster::Layout::kFlat) {
    text.emplace_back("planetsculpt:pixel_spacing_m", core::exactNumber(raster.pixelWidthM) + " " +
                                                          core::exactNumber(raster.pixelHeightM));
  }
  const std::vector<unsigned char> png = encodePng(img, {.text = text});
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f.write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
    if (!f) throw std::runtime_error("cannot write " + path.string());
  });
  nlohmann::json side = describe(raster, path, "png16");
  side["value_0_m"] = minM;
  side["value_65535_m"] = maxM;
  side["metres_per_unit"] = span / 65535.0;
  side["height_m"] = "value * metres_per_unit + value_0_m";
  writeSidecar(side, path);
}

void writeHeightTiff32(const Raster& raster, const std::filesystem::path& path) {
  checkRaster(raster, path);
  writeGdalGeoTiff(raster, path, "heights in metres; " + projectionText(raster));
  nlohmann::json side = describe(raster, path, "tiff-float32");
  writeSidecar(side, path);
}

void writeHeightRaw32(const Raster& raster, const std::filesystem::path& path) {
  checkRaster(raster, path);
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if constexpr (std::endian::native == std::endian::little) {
      f.write(reinterpret_cast<const char*>(raster.metres.data()),
              std::streamsize(raster.metres.size() * 4));
    } else {
      for (const float x : raster.metres) {
        char b[4];
        std::memcpy(b, &x, 4);
        std::reverse(b, b + 4);
        f.write(b, 4);
      }
    }
    f.close();
    if (!f) throw std::runtime_error("cannot write " + path.string() + " (disk full?)");
  });
  nlohmann::json side = describe(raster, path, "float32le");
  side["height_m"] = "value";
  writeSidecar(side, path);
}

// Hypsometric ramp (metres -> BGR): deep sea, shallow sea, lowland, upland, mountain, snow.
cv::Vec3f hypsometricTint(double h) {
  struct Stop {
    double h;
    float b, g, r;
  };
  static const Stop stops[] = {{-8000, 90, 30, 10},   {-3000, 160, 70, 25},  {-200, 210, 150, 70},
                               {0, 110, 160, 80},     {600, 70, 150, 120},   {2000, 60, 110, 150},
                               {4000, 100, 110, 130}, {6000, 235, 235, 240}, {9000, 255, 255, 255}};
  if (h <= stops[0].h) return {stops[0].b, stops[0].g, stops[0].r};
  for (std::size_t i = 1; i < std::size(stops); ++i) {
    if (h <= stops[i].h) {
      const double f = (h - stops[i - 1].h) / (stops[i].h - stops[i - 1].h);
      auto mix = [&](float a, float b) { return float(a + f * (b - a)); };
      return {mix(stops[i - 1].b, stops[i].b), mix(stops[i - 1].g, stops[i].g),
              mix(stops[i - 1].r, stops[i].r)};
    }
  }
  const Stop& s = stops[std::size(stops) - 1];
  return {s.b, s.g, s.r};
}

cv::Mat reliefImage(const Raster& raster, double metresPerPixel) {
  cv::Mat img(raster.height, raster.width, CV_8UC3);
  const int w = raster.width, hgt = raster.height;
  auto at = [&](int x, int y) {
    x = (x + w) % w;
    y = std::clamp(y, 0, hgt - 1);
    return double(raster.metres[std::size_t(y) * std::size_t(w) + std::size_t(x)]);
  };
  const Eigen::Vector3d light = Eigen::Vector3d(-1, -1, 1.5).normalized();
  for (int y = 0; y < hgt; ++y) {
    // East-west pixels shrink with cos(latitude).
    const double lat = (0.5 - (y + 0.5) / hgt) * M_PI;
    const double dxm = std::max(metresPerPixel * std::cos(lat), 1e-3 * metresPerPixel);
    for (int x = 0; x < w; ++x) {
      const double h = at(x, y);
      const double gx = (at(x + 1, y) - at(x - 1, y)) / (2 * dxm),
                   gy = (at(x, y + 1) - at(x, y - 1)) / (2 * metresPerPixel);
      const Eigen::Vector3d n =
          Eigen::Vector3d(-gx * 8, gy * 8, 1).normalized();  // 8x vertical exaggeration
      const double shade = h < 0 ? 0.85 + 0.15 * std::max(0.0, n.dot(light))
                                 : 0.35 + 0.75 * std::max(0.0, n.dot(light));
      const cv::Vec3f c = hypsometricTint(h) * float(shade);
      img.at<cv::Vec3b>(y, x) =
          cv::Vec3b(cv::saturate_cast<uchar>(c[0]), cv::saturate_cast<uchar>(c[1]),
                    cv::saturate_cast<uchar>(c[2]));
    }
  }
  return img;
}

void writeReliefPreview(const Raster& raster, double metresPerPixel,
                        const std::filesystem::path& path) {
  writePngAtomically(reliefImage(raster, metresPerPixel), path);
}

void writePngAtomically(const cv::Mat& img, const std::filesystem::path& path) {
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png))
    throw std::runtime_error("cannot encode PNG for " + path.string());
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f.write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
    if (!f) throw std::runtime_error("cannot write " + path.string());
  });
}

}  // namespace ps::io
