#include "io/height_image.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdarg>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "io/gdal_raster.hpp"
#include "io/png_codec.hpp"

namespace ps::io {

namespace {

[[noreturn]] void failImage(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

std::string imageDims(std::uint64_t w, std::uint64_t h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

void checkImageDims(std::uint64_t w, std::uint64_t h, const std::string& name,
                    std::uint64_t maxPixels = kMaxImagePixels) {
  if (w == 0 || h == 0) failImage(name, "image is " + imageDims(w, h) + " pixels: it is empty");
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > maxPixels) {
    failImage(name, "image is " + imageDims(w, h) + " pixels (" + std::to_string(w * h) +
                        "), more than this build accepts (" + std::to_string(maxPixels) +
                        " pixels, " + std::to_string(kMaxImageSide) +
                        " per side): crop or downsample it first");
  }
}

double parseNumberText(const std::string& s, bool& ok) {
  ok = false;
  std::string t = s;
  while (!t.empty() && (t.back() == '\0' || std::isspace(static_cast<unsigned char>(t.back())))) {
    t.pop_back();
  }
  std::size_t b = 0;
  while (b < t.size() && std::isspace(static_cast<unsigned char>(t[b]))) ++b;
  t = t.substr(b);
  std::string lower = t;
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (lower == "nan" || lower == "-nan") {
    ok = true;
    return std::numeric_limits<double>::quiet_NaN();
  }
  if (t.empty()) return 0;
  char* end = nullptr;
  const double x = std::strtod(t.c_str(), &end);
  ok = end == t.c_str() + t.size();
  return x;
}

// ---------------------------------------------------------------------------------------- PNG

// A web DEM tile: three 8-bit channels hold one height (see PngHeightEncoding).
HeightImage decodeRgbHeights(PngReader& reader, std::span<const unsigned char> b,
                             const std::string& name, PngHeightEncoding encoding) {
  const PngHeader& hd = reader.header();
  const std::string what = toString(encoding);
  if (hd.colourType != 2 && hd.colourType != 6 && hd.colourType != 3)
    failImage(name, "a " + what +
                        " tile must be an RGB, RGBA or palette PNG; this one has colour type " +
                        std::to_string(hd.colourType) + " (a grey heightmap needs no --encoding)");
  if (hd.bitDepth != 8 && !(hd.colourType == 3 && hd.bitDepth <= 8))
    failImage(name, "a " + what + " tile has 8-bit channels; this one has " +
                        std::to_string(hd.bitDepth) + "-bit samples");
  const std::uint64_t w = std::uint64_t(hd.width), h = std::uint64_t(hd.height);
  if (h * (1 + 4 * w) > 1032 * std::uint64_t(b.size()))
    failImage(name, "truncated PNG: " + std::to_string(b.size()) + " bytes cannot hold the " +
                        imageDims(std::uint32_t(w), std::uint32_t(h)) +
                        " pixels its header declares");
  cv::Mat m;
  try {
    m = reader.pixels();
  } catch (const PngError& e) {
    failImage(name, std::string("corrupt or truncated PNG: ") + e.what());
  }
  HeightImage img;
  img.kind = what + " PNG";
  img.width = m.cols;
  img.height = m.rows;
  img.values.resize(img.pixelCount());
  const int channels = m.channels();
  for (int y = 0; y < m.rows; ++y) {
    const std::uint8_t* row = m.ptr<std::uint8_t>(y);
    for (int x = 0; x < m.cols; ++x) {
      const double b0 = row[channels * x], g = row[channels * x + 1], r = row[channels * x + 2];
      img.values[std::size_t(y) * std::size_t(m.cols) + std::size_t(x)] =
          encoding == PngHeightEncoding::kTerrainRgb
              ? float(-10000.0 + (r * 65536.0 + g * 256.0 + b0) * 0.1)
              : float(r * 256.0 + g + b0 / 256.0 - 32768.0);
    }
  }
  return img;
}

HeightImage decodePng(std::span<const unsigned char> b, const std::string& name,
                      std::uint64_t maxPixels, PngHeightEncoding encoding) {
  std::optional<PngReader> reader;
  try {
    reader.emplace(b);
  } catch (const PngError& e) {
    failImage(name, std::string("truncated PNG, or a corrupt header (") + e.what() + ")");
  }
  const PngHeader& hd = reader->header();
  const std::uint32_t w = std::uint32_t(hd.width), h = std::uint32_t(hd.height);
  const int depth = hd.bitDepth, colour = hd.colourType;
  checkImageDims(w, h, name, maxPixels);
  if (encoding != PngHeightEncoding::kStored) return decodeRgbHeights(*reader, b, name, encoding);
  if (colour != 0) {
    static const char* kinds[] = {"grey", "?", "RGB", "palette", "grey+alpha", "?", "RGBA"};
    failImage(name, std::string("PNG colour type ") + std::to_string(colour) + " (" +
                        (colour <= 6 ? kinds[colour] : "invalid") +
                        "): a heightmap must be a single-channel grey PNG (8 or 16 bits), or a web "
                        "DEM tile read with --encoding terrain-rgb or terrarium");
  }
  if (depth != 8 && depth != 16) {
    failImage(name,
              "grey PNG with " + std::to_string(depth) + "-bit samples: 8 and 16 are supported");
  }
  // Deflate expands at most 1032:1 (two bits per 258-byte match), so a file too small to hold
  // its filtered rows is refused before the decoder allocates for them.
  const std::uint64_t rowBytes = 1 + std::uint64_t(w) * std::uint64_t(depth / 8);
  if (std::uint64_t(h) * rowBytes > 1032 * std::uint64_t(b.size())) {
    failImage(name, "truncated PNG: " + std::to_string(b.size()) + " bytes cannot hold the " +
                        imageDims(w, h) + " pixels its header declares");
  }
  cv::Mat m;
  try {
    m = reader->pixels();
  } catch (const PngError& e) {
    failImage(name, std::string("corrupt or truncated PNG: ") + e.what());
  }
  HeightImage img;
  img.kind = std::to_string(depth) + "-bit grey PNG";
  const PngText text = reader->text();
  for (const auto& [key, value] : text) {
    bool ok = false;
    const double x = parseNumberText(value, ok);
    if (key == "planetsculpt:min_m" && ok && std::isfinite(x)) img.value0Metres = x;
    if (key == "planetsculpt:max_m" && ok && std::isfinite(x)) img.value65535Metres = x;
    if (key == "planetsculpt:projection") {
      img.projection = value.rfind("flat", 0) == 0       ? "flat"
                       : value.rfind("torus", 0) == 0    ? "torus"
                       : value.rfind("cylinder", 0) == 0 ? "cylinder"
                                                         : "equirectangular";
    }
    if (key == "planetsculpt:pixel_spacing_m") {
      double sx = 0, sy = 0;
      char tail = 0;
      if (std::sscanf(value.c_str(), "%lf %lf %c", &sx, &sy, &tail) == 2 && std::isfinite(sx) &&
          std::isfinite(sy) && sx > 0 && sy > 0) {
        img.pixelSpacingX = sx;
        img.pixelSpacingY = sy;
      }
    }
  }
  img.width = int(w);
  img.height = int(h);
  img.values.resize(img.pixelCount());
  cv::Mat f(m.rows, m.cols, CV_32F, img.values.data());
  m.convertTo(f, CV_32F);
  return img;
}

double numberField(const nlohmann::json& j, const char* key, const std::string& name) {
  const auto& v = j.at(key);
  if (!v.is_number()) failImage(name, std::string("sidecar field '") + key + "' must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) failImage(name, std::string("sidecar field '") + key + "' is not finite");
  return x;
}

}  // namespace

ImageFormat sniffFormat(std::span<const unsigned char> b) {
  if (b.size() >= 8 && std::memcmp(b.data(), "\x89PNG\r\n\x1a\n", 8) == 0) return ImageFormat::kPng;
  if (b.size() >= 4 &&
      (std::memcmp(b.data(), "II*\0", 4) == 0 || std::memcmp(b.data(), "MM\0*", 4) == 0 ||
       std::memcmp(b.data(), "II+\0", 4) == 0 || std::memcmp(b.data(), "MM\0+", 4) == 0)) {
    return ImageFormat::kTiff;
  }
  if (b.size() >= 8 && std::memcmp(b.data(), "\x89PSP\r\n\x1a\n", 8) == 0)
    return ImageFormat::kPlanet;
  return ImageFormat::kUnknown;
}

namespace {
constexpr core::NameTable<PngHeightEncoding, 3> kEncodings{
    "PNG height encoding",
    {{{PngHeightEncoding::kStored, "stored"},
      {PngHeightEncoding::kTerrainRgb, "terrain-rgb"},
      {PngHeightEncoding::kTerrarium, "terrarium"}}}};
}  // namespace

std::string toString(PngHeightEncoding e) {
  return kEncodings.nameOf(e);
}

PngHeightEncoding pngHeightEncodingFromString(const std::string& s) {
  return kEncodings.parse(s);
}

HeightImage decodeHeightImage(std::span<const unsigned char> bytes, const std::string& name,
                              std::uint64_t maxPixels, PngHeightEncoding encoding) {
  if (bytes.empty()) failImage(name, "empty file (0 bytes)");
  maxPixels = std::min(maxPixels, kMaxImagePixels);
  const ImageFormat format = sniffFormat(bytes);
  if (encoding != PngHeightEncoding::kStored && format != ImageFormat::kPng)
    failImage(name,
              "--encoding " + toString(encoding) + " applies to PNG tiles; this is not a PNG");
  switch (format) {
    case ImageFormat::kPng:
      return decodePng(bytes, name, maxPixels, encoding);
    case ImageFormat::kTiff:
      return decodeGdalTiff(bytes, name, maxPixels);
    case ImageFormat::kPlanet:
      failImage(name, "this is a planet file, not a heightmap image");
    default:
      break;
  }
  failImage(name, "not a PNG or TIFF image (unrecognised first bytes)");
}

RawSidecar parseRawSidecar(std::string_view text, const std::string& name) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) failImage(name, "sidecar is not valid JSON");
  if (!j.is_object()) failImage(name, "sidecar must be a JSON object");
  RawSidecar s;
  if (!j.contains("format") || !j["format"].is_string()) {
    failImage(name, "sidecar has no \"format\" string (expected \"float32le\")");
  }
  const std::string format = j["format"].get<std::string>();
  if (format != "float32le") {
    failImage(name, "sidecar format '" + format + "' is not supported (expected \"float32le\")");
  }
  for (const char* key : {"width", "height"}) {
    if (!j.contains(key)) failImage(name, std::string("sidecar has no \"") + key + "\"");
    const auto& v = j[key];
    if (!v.is_number_integer() || v.get<std::int64_t>() <= 0) {
      failImage(name, std::string("sidecar \"") + key + "\" must be a positive integer");
    }
    if (v.get<std::int64_t>() > std::int64_t(kMaxImageSide)) {
      checkImageDims(std::uint64_t(v.get<std::int64_t>()), 1, name);
    }
  }
  const auto w = j["width"].get<std::int64_t>(), h = j["height"].get<std::int64_t>();
  checkImageDims(std::uint64_t(w), std::uint64_t(h), name);
  s.width = int(w);
  s.height = int(h);
  if (j.contains("nodata") && !j["nodata"].is_null()) {
    const auto& v = j["nodata"];
    if (v.is_string() && (v.get<std::string>() == "nan" || v.get<std::string>() == "NaN")) {
      s.noData = std::numeric_limits<double>::quiet_NaN();
    } else if (v.is_number()) {
      s.noData = v.get<double>();
    } else {
      failImage(name, "sidecar \"nodata\" must be a number or \"nan\"");
    }
  }
  if (j.contains("column0_longitude_deg"))
    s.column0LongitudeDeg = numberField(j, "column0_longitude_deg", name);
  if (j.contains("projection")) {
    if (!j["projection"].is_string()) failImage(name, "sidecar \"projection\" must be a string");
    s.projection = j["projection"].get<std::string>();
    if (s.projection != "equirectangular" && s.projection != "flat" && s.projection != "torus" &&
        s.projection != "cylinder") {
      failImage(name, "sidecar projection '" + s.projection +
                          "' is unknown (equirectangular, flat, torus or cylinder)");
    }
  }
  if (j.contains("radius_m")) {
    s.radiusMetres = numberField(j, "radius_m", name);
    if (!(*s.radiusMetres > 0)) failImage(name, "sidecar \"radius_m\" must be positive");
  }
  for (const auto& [key, field] : {std::pair{"minor_radius_m", &s.minorRadiusMetres},
                                   std::pair{"length_m", &s.lengthMetres}}) {
    if (!j.contains(key)) continue;
    *field = numberField(j, key, name);
    if (!(**field > 0)) failImage(name, std::string("sidecar \"") + key + "\" must be positive");
  }
  if (j.contains("pixel_spacing_m")) {
    const auto& v = j["pixel_spacing_m"];
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() ||
        !(v[0].get<double>() > 0) || !(v[1].get<double>() > 0) ||
        !std::isfinite(v[0].get<double>()) || !std::isfinite(v[1].get<double>())) {
      failImage(name, "sidecar \"pixel_spacing_m\" must be two positive numbers");
    }
    s.pixelSpacingX = v[0].get<double>();
    s.pixelSpacingY = v[1].get<double>();
  }
  return s;
}

HeightImage decodeRaw(std::span<const unsigned char> bytes, const RawSidecar& s,
                      const std::string& name) {
  const std::uint64_t want = std::uint64_t(s.width) * std::uint64_t(s.height) * 4;
  if (bytes.size() != want) {
    failImage(name, std::string(bytes.size() < want ? "truncated: " : "too long: ") +
                        std::to_string(bytes.size()) + " bytes, the sidecar's " +
                        imageDims(std::uint64_t(s.width), std::uint64_t(s.height)) +
                        " float32 raster needs " + std::to_string(want));
  }
  HeightImage img;
  img.kind = "float32 raw";
  img.width = s.width;
  img.height = s.height;
  img.values.resize(img.pixelCount());
  for (std::size_t i = 0; i < img.values.size(); ++i) {
    unsigned char b[4];
    std::memcpy(b, bytes.data() + 4 * i, 4);
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + 4);
    std::memcpy(&img.values[i], b, 4);
  }
  if (s.noData) {
    img.noData = s.noData;
    img.noDataSource = "sidecar \"nodata\"";
  }
  img.column0LongitudeDeg = s.column0LongitudeDeg;
  img.projection = s.projection;
  img.pixelSpacingX = s.pixelSpacingX;
  img.pixelSpacingY = s.pixelSpacingY;
  img.radiusMetres = s.radiusMetres;
  img.minorRadiusMetres = s.minorRadiusMetres;
  img.lengthMetres = s.lengthMetres;
  return img;
}

std::vector<unsigned char> readFileBytes(const std::filesystem::path& path,
                                         std::uint64_t maxBytes) {
  const std::string name = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) failImage(name, "no such file");
  if (std::filesystem::is_directory(status)) failImage(name, "is a directory");
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) failImage(name, "cannot read its size: " + ec.message());
  if (size > maxBytes) {
    failImage(name, "file is " + std::to_string(size) + " bytes, more than the " +
                        std::to_string(maxBytes) + " this reader accepts");
  }
  std::ifstream f(path, std::ios::binary);
  if (!f) failImage(name, "cannot open for reading");
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  f.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size));
  if (std::uint64_t(f.gcount()) != size) failImage(name, "read error");
  return bytes;
}

namespace {

// Up to n bytes from the start of a file (what sniffFormat needs); "no such file" as readFileBytes.
std::vector<unsigned char> readFileHead(const std::filesystem::path& path, std::size_t n) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) failImage(path.string(), "no such file");
  std::ifstream f(path, std::ios::binary);
  if (!f) failImage(path.string(), "cannot open for reading");
  std::vector<unsigned char> head(n);
  f.read(reinterpret_cast<char*>(head.data()), std::streamsize(n));
  head.resize(std::size_t(f.gcount()));
  return head;
}

}  // namespace

HeightImage readHeightImage(const std::filesystem::path& path, PngHeightEncoding encoding) {
  const std::string name = path.string();
  if (encoding != PngHeightEncoding::kStored)
    return decodeHeightImage(readFileBytes(path), name, kMaxImagePixels, encoding);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return readGdalRaster(path);  // an ESRI grid
  // PNG (with this project's tEXt metadata) and raw float32 (with its sidecar) are read here;
  // TIFF and everything else GDAL opens (PDS3 with its label, SRTM .hgt, ESRI grids, netCDF ...)
  // through GDAL, from the path, so that it finds a format's sibling files.
  const std::vector<unsigned char> head = readFileHead(path, 16);
  const ImageFormat format = sniffFormat(head);
  if (format == ImageFormat::kPng || format == ImageFormat::kPlanet) {
    return decodeHeightImage(readFileBytes(path), name);
  }
  if (format == ImageFormat::kTiff) return readGdalRaster(path, kMaxImagePixels, true);
  auto sidecar = path;
  sidecar += ".json";
  if (std::filesystem::exists(sidecar)) {
    const auto text = readFileBytes(sidecar, 1 << 20);
    const RawSidecar s =
        parseRawSidecar(std::string_view(reinterpret_cast<const char*>(text.data()), text.size()),
                        sidecar.string());
    return decodeRaw(readFileBytes(path), s, name);
  }
  if (head.empty()) failImage(name, "empty file (0 bytes)");
  try {
    return readGdalRaster(path);
  } catch (const core::InputError& e) {
    const std::string why = e.what();
    if (why.find("not a raster GDAL can open") == std::string::npos) throw;
  }
  failImage(name, "not a PNG or TIFF image, nor a raster GDAL opens, and no sidecar " +
                      sidecar.filename().string() +
                      " describes it as raw float32: cannot tell what it holds");
}

}  // namespace ps::io
