#include "io/height_image.hpp"

#include <tiffio.h>

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
#include "io/png_codec.hpp"

namespace ps::io {

namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

std::string dims(std::uint64_t w, std::uint64_t h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

void checkDims(std::uint64_t w, std::uint64_t h, const std::string& name,
               std::uint64_t maxPixels = kMaxImagePixels) {
  if (w == 0 || h == 0) fail(name, "image is " + dims(w, h) + " pixels: it is empty");
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > maxPixels) {
    fail(name, "image is " + dims(w, h) + " pixels (" + std::to_string(w * h) +
                   "), more than this build accepts (" + std::to_string(maxPixels) + " pixels, " +
                   std::to_string(kMaxImageSide) + " per side): crop or downsample it first");
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

HeightImage decodePng(std::span<const unsigned char> b, const std::string& name,
                      std::uint64_t maxPixels) {
  std::optional<PngReader> reader;
  try {
    reader.emplace(b);
  } catch (const PngError& e) {
    fail(name, std::string("truncated PNG, or a corrupt header (") + e.what() + ")");
  }
  const PngHeader& hd = reader->header();
  const std::uint32_t w = std::uint32_t(hd.width), h = std::uint32_t(hd.height);
  const int depth = hd.bitDepth, colour = hd.colourType;
  checkDims(w, h, name, maxPixels);
  if (colour != 0) {
    static const char* kinds[] = {"grey", "?", "RGB", "palette", "grey+alpha", "?", "RGBA"};
    fail(name, std::string("PNG colour type ") + std::to_string(colour) + " (" +
                   (colour <= 6 ? kinds[colour] : "invalid") +
                   "): a heightmap must be a single-channel grey PNG (8 or 16 bits)");
  }
  if (depth != 8 && depth != 16) {
    fail(name, "grey PNG with " + std::to_string(depth) + "-bit samples: 8 and 16 are supported");
  }
  // Deflate expands at most 1032:1 (two bits per 258-byte match), so a file too small to hold
  // its filtered rows is refused before the decoder allocates for them.
  const std::uint64_t rowBytes = 1 + std::uint64_t(w) * std::uint64_t(depth / 8);
  if (std::uint64_t(h) * rowBytes > 1032 * std::uint64_t(b.size())) {
    fail(name, "truncated PNG: " + std::to_string(b.size()) + " bytes cannot hold the " +
                   dims(w, h) + " pixels its header declares");
  }
  cv::Mat m;
  try {
    m = reader->pixels();
  } catch (const PngError& e) {
    fail(name, std::string("corrupt or truncated PNG: ") + e.what());
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
      img.projection = value.rfind("flat", 0) == 0 ? "flat" : "equirectangular";
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

// --------------------------------------------------------------------------------------- TIFF

struct MemStream {
  const unsigned char* data;
  std::uint64_t size;
  std::uint64_t pos = 0;
};

tmsize_t memRead(thandle_t h, void* buf, tmsize_t n) {
  auto* s = static_cast<MemStream*>(h);
  if (n <= 0 || s->pos >= s->size) return 0;
  const std::uint64_t k = std::min<std::uint64_t>(std::uint64_t(n), s->size - s->pos);
  std::memcpy(buf, s->data + s->pos, std::size_t(k));
  s->pos += k;
  return tmsize_t(k);
}
tmsize_t memWrite(thandle_t, void*, tmsize_t) {
  return 0;
}
toff_t memSeek(thandle_t h, toff_t off, int whence) {
  auto* s = static_cast<MemStream*>(h);
  std::uint64_t base = 0;
  if (whence == SEEK_CUR) base = s->pos;
  if (whence == SEEK_END) base = s->size;
  if (off > std::numeric_limits<std::uint64_t>::max() - base) return toff_t(-1);
  s->pos = base + off;
  return s->pos;
}
int memClose(thandle_t) {
  return 0;
}
toff_t memSize(thandle_t h) {
  return static_cast<MemStream*>(h)->size;
}
int memMap(thandle_t, void**, toff_t*) {
  return 0;
}
void memUnmap(thandle_t, void*, toff_t) {}

int collectError(TIFF*, void* user, const char* module, const char* fmt, va_list ap) {
  auto* msg = static_cast<std::string*>(user);
  if (msg->empty()) {
    char buf[512];
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    *msg = (module && *module ? std::string(module) + ": " : std::string()) + buf;
  }
  return 1;
}
int ignoreWarning(TIFF*, void*, const char*, const char*, va_list) {
  return 1;
}

struct TiffCloser {
  void operator()(TIFF* t) const { TIFFClose(t); }
};

template <class T>
float sampleAs(const unsigned char* p) {
  T x;
  std::memcpy(&x, p, sizeof(T));
  return float(x);
}

// Reads the anonymous (auto-registered) GeoTIFF double arrays.
bool getDoubles(TIFF* t, ttag_t tag, std::vector<double>& out) {
  const TIFFField* field = TIFFFindField(t, tag, TIFF_ANY);
  if (!field || TIFFFieldDataType(field) != TIFF_DOUBLE || !TIFFFieldPassCount(field)) return false;
  void* data = nullptr;
  if (TIFFFieldReadCount(field) == TIFF_VARIABLE2) {
    std::uint32_t n = 0;
    if (!TIFFGetField(t, tag, &n, &data) || !data) return false;
    out.assign(static_cast<double*>(data), static_cast<double*>(data) + n);
  } else {
    std::uint16_t n = 0;
    if (!TIFFGetField(t, tag, &n, &data) || !data) return false;
    out.assign(static_cast<double*>(data), static_cast<double*>(data) + n);
  }
  return true;
}

bool getShorts(TIFF* t, ttag_t tag, std::vector<std::uint16_t>& out) {
  const TIFFField* field = TIFFFindField(t, tag, TIFF_ANY);
  if (!field || TIFFFieldDataType(field) != TIFF_SHORT || !TIFFFieldPassCount(field)) return false;
  void* data = nullptr;
  if (TIFFFieldReadCount(field) == TIFF_VARIABLE2) {
    std::uint32_t n = 0;
    if (!TIFFGetField(t, tag, &n, &data) || !data) return false;
    out.assign(static_cast<std::uint16_t*>(data), static_cast<std::uint16_t*>(data) + n);
  } else {
    std::uint16_t n = 0;
    if (!TIFFGetField(t, tag, &n, &data) || !data) return false;
    out.assign(static_cast<std::uint16_t*>(data), static_cast<std::uint16_t*>(data) + n);
  }
  return true;
}

// The GDAL_NODATA tag (42113, ASCII). libtiff's registration of it passes a count or not
// depending on the version: ask the field.
std::optional<std::string> gdalNoData(TIFF* t) {
  const TIFFField* field = TIFFFindField(t, TIFFTAG_GDAL_NODATA, TIFF_ANY);
  if (!field || TIFFFieldDataType(field) != TIFF_ASCII) return std::nullopt;
  char* text = nullptr;
  std::uint32_t count = 0;
  if (TIFFFieldPassCount(field)) {
    if (TIFFFieldReadCount(field) == TIFF_VARIABLE2) {
      if (!TIFFGetField(t, TIFFTAG_GDAL_NODATA, &count, &text) || !text) return std::nullopt;
    } else {
      std::uint16_t n16 = 0;
      if (!TIFFGetField(t, TIFFTAG_GDAL_NODATA, &n16, &text) || !text) return std::nullopt;
      count = n16;
    }
    return std::string(text, strnlen(text, count));
  }
  if (!TIFFGetField(t, TIFFTAG_GDAL_NODATA, &text) || !text) return std::nullopt;
  return std::string(text);
}

std::optional<GeoReference> readGeoReference(TIFF* t) {
  std::vector<double> scale, tie;
  if (!getDoubles(t, 33550, scale) || !getDoubles(t, 33922, tie)) return std::nullopt;
  if (scale.size() < 2 || tie.size() < 6) return std::nullopt;
  GeoReference g;
  g.pixelScaleX = scale[0];
  g.pixelScaleY = scale[1];
  // Tie point (i, j, k) -> (x, y, z): the top-left corner is (x - i * sx, y + j * sy).
  g.originX = tie[3] - tie[0] * g.pixelScaleX;
  g.originY = tie[4] + tie[1] * g.pixelScaleY;
  std::vector<std::uint16_t> keys;
  std::vector<double> doubles;
  getDoubles(t, 34736, doubles);
  if (getShorts(t, 34735, keys) && keys.size() >= 4) {
    const std::size_t n = keys[3];
    std::optional<double> major, minor;
    bool pixelIsPoint = false;
    for (std::size_t k = 0; k < n && 4 + 4 * k + 3 < keys.size(); ++k) {
      const std::uint16_t* e = keys.data() + 4 + 4 * k;
      if (e[0] == 1024 && e[1] == 0) g.geographic = e[3] == 2;  // GTModelTypeGeoKey
      if (e[0] == 1025 && e[1] == 0) pixelIsPoint = e[3] == 2;  // GTRasterTypeGeoKey
      // GeogSemiMajorAxisGeoKey / GeogSemiMinorAxisGeoKey, stored in GeoDoubleParams.
      if ((e[0] == 2057 || e[0] == 2058) && e[1] == 34736 && e[2] == 1 && e[3] < doubles.size()) {
        (e[0] == 2057 ? major : minor) = doubles[e[3]];
      }
    }
    if (major && minor && *major == *minor && std::isfinite(*major) && *major > 0) {
      g.sphereRadius = *major;
    }
    // Pixel-is-point: the tie point is a pixel's centre; the raster's corner is half a pixel out.
    if (pixelIsPoint) {
      g.originX -= 0.5 * g.pixelScaleX;
      g.originY += 0.5 * g.pixelScaleY;
    }
  }
  for (double x : {g.pixelScaleX, g.pixelScaleY, g.originX, g.originY}) {
    if (!std::isfinite(x)) return std::nullopt;
  }
  if (g.pixelScaleX <= 0 || g.pixelScaleY <= 0) return std::nullopt;
  return g;
}

HeightImage decodeTiff(std::span<const unsigned char> b, const std::string& name,
                       std::uint64_t maxPixels) {
  MemStream stream{b.data(), b.size()};
  std::string error;
  TIFFOpenOptions* opts = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(opts, collectError, &error);
  TIFFOpenOptionsSetWarningHandlerExtR(opts, ignoreWarning, nullptr);
  TIFFOpenOptionsSetMaxSingleMemAlloc(opts, tmsize_t(1) << 30);
  std::unique_ptr<TIFF, TiffCloser> tif(TIFFClientOpenExt(name.c_str(), "rm", &stream, memRead,
                                                          memWrite, memSeek, memClose, memSize,
                                                          memMap, memUnmap, opts));
  TIFFOpenOptionsFree(opts);
  if (!tif) fail(name, "corrupt or truncated TIFF" + (error.empty() ? "" : " (" + error + ")"));
  TIFF* t = tif.get();
  std::uint32_t w = 0, h = 0;
  std::uint16_t bits = 1, spp = 1, format = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG;
  if (!TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &w) || !TIFFGetField(t, TIFFTAG_IMAGELENGTH, &h)) {
    fail(name, "TIFF has no image width or length tag");
  }
  checkDims(w, h, name, maxPixels);
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(t, TIFFTAG_PLANARCONFIG, &planar);
  if (spp != 1) {
    fail(name, "TIFF has " + std::to_string(spp) +
                   " samples per pixel: a heightmap must have one (a single band)");
  }
  std::string type;
  float (*convert)(const unsigned char*) = nullptr;
  if (format == SAMPLEFORMAT_UINT || format == SAMPLEFORMAT_VOID) {
    if (bits == 8) convert = sampleAs<std::uint8_t>, type = "uint8";
    if (bits == 16) convert = sampleAs<std::uint16_t>, type = "uint16";
    if (bits == 32) convert = sampleAs<std::uint32_t>, type = "uint32";
  } else if (format == SAMPLEFORMAT_INT) {
    if (bits == 8) convert = sampleAs<std::int8_t>, type = "int8";
    if (bits == 16) convert = sampleAs<std::int16_t>, type = "int16";
    if (bits == 32) convert = sampleAs<std::int32_t>, type = "int32";
  } else if (format == SAMPLEFORMAT_IEEEFP) {
    if (bits == 32) convert = sampleAs<float>, type = "float32";
    if (bits == 64) convert = sampleAs<double>, type = "float64";
  }
  if (!convert) {
    fail(name, "TIFF sample type (" + std::to_string(bits) + " bits, sample format " +
                   std::to_string(format) +
                   ") is not supported: use 8/16/32-bit integers or 32/64-bit floats");
  }
  HeightImage img;
  img.kind = type + " TIFF";
  img.width = int(w);
  img.height = int(h);
  const std::size_t bytesPer = bits / 8;
  std::uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &compression);
  // Uncompressed samples cannot be fewer bytes than the file: say so before allocating for them.
  if (compression == COMPRESSION_NONE && std::uint64_t(w) * h * bytesPer > b.size()) {
    fail(name, "truncated TIFF: " + dims(w, h) + " uncompressed " + type + " samples need " +
                   std::to_string(std::uint64_t(w) * h * bytesPer) + " bytes, the file has " +
                   std::to_string(b.size()));
  }

  if (const std::optional<std::string> nodata = gdalNoData(t)) {
    bool ok = false;
    const double x = parseNumberText(*nodata, ok);
    if (!ok) fail(name, "GDAL_NODATA tag holds '" + *nodata + "', which is not a number");
    img.noData = x;
    img.noDataSource = "GDAL_NODATA tag";
  }
  img.geo = readGeoReference(t);
  if (img.geo && img.geo->sphereRadius) img.radiusMetres = img.geo->sphereRadius;

  img.values.resize(img.pixelCount());
  auto bad = [&](const std::string& what) {
    fail(name, what + (error.empty() ? "" : " (" + error + ")"));
  };
  if (TIFFIsTiled(t)) {
    std::uint32_t tw = 0, th = 0;
    TIFFGetField(t, TIFFTAG_TILEWIDTH, &tw);
    TIFFGetField(t, TIFFTAG_TILELENGTH, &th);
    if (tw == 0 || th == 0) bad("TIFF tile size is 0");
    // Tiles are multiples of 16 pixels; one larger than the image rounded up to that is corrupt
    // (and would make us allocate for pixels that do not exist).
    const auto roundUp16 = [](std::uint64_t x) { return (x + 15) / 16 * 16; };
    if (tw > roundUp16(w) || th > roundUp16(h)) {
      bad("TIFF tile is " + dims(tw, th) + " pixels, larger than the " + dims(w, h) + " image");
    }
    const tmsize_t tileBytes = TIFFTileSize(t);
    if (tileBytes <= 0 || std::uint64_t(tileBytes) < std::uint64_t(tw) * th * bytesPer) {
      bad("TIFF tile size is inconsistent");
    }
    std::vector<unsigned char> buf(static_cast<std::size_t>(tileBytes));
    for (std::uint32_t y0 = 0; y0 < h; y0 += th) {
      for (std::uint32_t x0 = 0; x0 < w; x0 += tw) {
        const tmsize_t got =
            TIFFReadEncodedTile(t, TIFFComputeTile(t, x0, y0, 0, 0), buf.data(), tileBytes);
        if (got < 0)
          bad("corrupt or truncated TIFF: cannot read the tile at (" + std::to_string(x0) + ", " +
              std::to_string(y0) + ")");
        for (std::uint32_t y = y0; y < std::min(h, y0 + th); ++y) {
          for (std::uint32_t x = x0; x < std::min(w, x0 + tw); ++x) {
            const std::size_t off = (std::size_t(y - y0) * tw + (x - x0)) * bytesPer;
            img.values[std::size_t(y) * w + x] = convert(buf.data() + off);
          }
        }
      }
    }
  } else {
    std::uint32_t rps = 0;
    TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &rps);
    rps = std::clamp<std::uint32_t>(rps, 1, h);
    const tmsize_t stripBytes = TIFFStripSize(t);
    if (stripBytes <= 0) bad("TIFF strip size is inconsistent");
    std::vector<unsigned char> buf(static_cast<std::size_t>(stripBytes));
    const std::uint32_t strips = TIFFNumberOfStrips(t);
    for (std::uint32_t y0 = 0, s = 0; y0 < h; y0 += rps, ++s) {
      if (s >= strips) bad("TIFF has fewer strips than its height needs");
      const std::uint32_t rows = std::min(rps, h - y0);
      const std::uint64_t need = std::uint64_t(rows) * w * bytesPer;
      const tmsize_t got = TIFFReadEncodedStrip(t, s, buf.data(), stripBytes);
      if (got < 0 || std::uint64_t(got) < need) {
        bad("corrupt or truncated TIFF: strip " + std::to_string(s) + " (rows " +
            std::to_string(y0) + "..) is short or unreadable");
      }
      for (std::size_t i = 0; i < std::size_t(rows) * w; ++i) {
        img.values[std::size_t(y0) * w + i] = convert(buf.data() + i * bytesPer);
      }
    }
  }
  return img;
}

double numberField(const nlohmann::json& j, const char* key, const std::string& name) {
  const auto& v = j.at(key);
  if (!v.is_number()) fail(name, std::string("sidecar field '") + key + "' must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(name, std::string("sidecar field '") + key + "' is not finite");
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

HeightImage decodeHeightImage(std::span<const unsigned char> bytes, const std::string& name,
                              std::uint64_t maxPixels) {
  if (bytes.empty()) fail(name, "empty file (0 bytes)");
  maxPixels = std::min(maxPixels, kMaxImagePixels);
  switch (sniffFormat(bytes)) {
    case ImageFormat::kPng:
      return decodePng(bytes, name, maxPixels);
    case ImageFormat::kTiff:
      return decodeTiff(bytes, name, maxPixels);
    case ImageFormat::kPlanet:
      fail(name, "this is a planet file, not a heightmap image");
    default:
      break;
  }
  fail(name, "not a PNG or TIFF image (unrecognised first bytes)");
}

RawSidecar parseRawSidecar(std::string_view text, const std::string& name) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) fail(name, "sidecar is not valid JSON");
  if (!j.is_object()) fail(name, "sidecar must be a JSON object");
  RawSidecar s;
  if (!j.contains("format") || !j["format"].is_string()) {
    fail(name, "sidecar has no \"format\" string (expected \"float32le\")");
  }
  const std::string format = j["format"].get<std::string>();
  if (format != "float32le") {
    fail(name, "sidecar format '" + format + "' is not supported (expected \"float32le\")");
  }
  for (const char* key : {"width", "height"}) {
    if (!j.contains(key)) fail(name, std::string("sidecar has no \"") + key + "\"");
    const auto& v = j[key];
    if (!v.is_number_integer() || v.get<std::int64_t>() <= 0) {
      fail(name, std::string("sidecar \"") + key + "\" must be a positive integer");
    }
    if (v.get<std::int64_t>() > std::int64_t(kMaxImageSide)) {
      checkDims(std::uint64_t(v.get<std::int64_t>()), 1, name);
    }
  }
  const auto w = j["width"].get<std::int64_t>(), h = j["height"].get<std::int64_t>();
  checkDims(std::uint64_t(w), std::uint64_t(h), name);
  s.width = int(w);
  s.height = int(h);
  if (j.contains("nodata") && !j["nodata"].is_null()) {
    const auto& v = j["nodata"];
    if (v.is_string() && (v.get<std::string>() == "nan" || v.get<std::string>() == "NaN")) {
      s.noData = std::numeric_limits<double>::quiet_NaN();
    } else if (v.is_number()) {
      s.noData = v.get<double>();
    } else {
      fail(name, "sidecar \"nodata\" must be a number or \"nan\"");
    }
  }
  if (j.contains("column0_longitude_deg"))
    s.column0LongitudeDeg = numberField(j, "column0_longitude_deg", name);
  if (j.contains("projection")) {
    if (!j["projection"].is_string()) fail(name, "sidecar \"projection\" must be a string");
    s.projection = j["projection"].get<std::string>();
    if (s.projection != "equirectangular" && s.projection != "flat") {
      fail(name, "sidecar projection '" + s.projection + "' is unknown (equirectangular or flat)");
    }
  }
  if (j.contains("radius_m")) {
    s.radiusMetres = numberField(j, "radius_m", name);
    if (!(*s.radiusMetres > 0)) fail(name, "sidecar \"radius_m\" must be positive");
  }
  if (j.contains("pixel_spacing_m")) {
    const auto& v = j["pixel_spacing_m"];
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() ||
        !(v[0].get<double>() > 0) || !(v[1].get<double>() > 0) ||
        !std::isfinite(v[0].get<double>()) || !std::isfinite(v[1].get<double>())) {
      fail(name, "sidecar \"pixel_spacing_m\" must be two positive numbers");
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
    fail(name, std::string(bytes.size() < want ? "truncated: " : "too long: ") +
                   std::to_string(bytes.size()) + " bytes, the sidecar's " +
                   dims(std::uint64_t(s.width), std::uint64_t(s.height)) +
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
  return img;
}

std::vector<unsigned char> readFileBytes(const std::filesystem::path& path,
                                         std::uint64_t maxBytes) {
  const std::string name = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) fail(name, "no such file");
  if (std::filesystem::is_directory(status)) fail(name, "is a directory");
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) fail(name, "cannot read its size: " + ec.message());
  if (size > maxBytes) {
    fail(name, "file is " + std::to_string(size) + " bytes, more than the " +
                   std::to_string(maxBytes) + " this reader accepts");
  }
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(name, "cannot open for reading");
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  f.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size));
  if (std::uint64_t(f.gcount()) != size) fail(name, "read error");
  return bytes;
}

HeightImage readHeightImage(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::vector<unsigned char> bytes = readFileBytes(path);
  const ImageFormat format = sniffFormat(bytes);
  if (format == ImageFormat::kPng || format == ImageFormat::kTiff ||
      format == ImageFormat::kPlanet) {
    return decodeHeightImage(bytes, name);
  }
  auto sidecar = path;
  sidecar += ".json";
  if (std::filesystem::exists(sidecar)) {
    const auto text = readFileBytes(sidecar, 1 << 20);
    const RawSidecar s =
        parseRawSidecar(std::string_view(reinterpret_cast<const char*>(text.data()), text.size()),
                        sidecar.string());
    return decodeRaw(bytes, s, name);
  }
  if (bytes.empty()) fail(name, "empty file (0 bytes)");
  fail(name, "not a PNG or TIFF image, and no sidecar " + sidecar.filename().string() +
                 " describes it as raw float32: cannot tell what it holds");
}

}  // namespace ps::io
