#include "io/planet_file.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>

#include "core/chart_factory.hpp"
#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "core/octahedral_chart.hpp"
#include "io/atomic_file.hpp"

namespace ps::io {

namespace {

// 0x89 (not ASCII), "PSP", CR LF, ^Z, LF: like PNG's magic, it catches text-mode transfers.
constexpr unsigned char kMagic[8] = {0x89, 'P', 'S', 'P', '\r', '\n', 0x1a, '\n'};
constexpr std::size_t kChartNameBytes = 16;

// Fuzz builds (the libFuzzer convention's macro, set by fuzz/CMakeLists.txt) accept wrong
// checksums, so mutated inputs reach the checks behind them.
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr bool kSkipChecksums = true;
#else
constexpr bool kSkipChecksums = false;
#endif

// Header layout (byte offsets); docs/PLANET-FILE.md has the same table.
enum Offset : std::size_t {
  kOffMagic = 0,
  kOffVersion = 8,
  kOffHeaderBytes = 12,
  kOffChart = 16,
  kOffSide = 32,
  kOffEncoding = 36,
  kOffRadius = 40,
  kOffDx = 48,
  kOffDy = 56,
  kOffScale = 64,
  kOffOffset = 72,
  kOffRule = 80,
  kOffMetadataBytes = 84,
  kOffHeightBytes = 88,
  kOffBodyCrc = 96,
  kOffReserved = 100,   // version 1: zero up to the header's CRC
  kOffVariant = 100,    // version 2: the chart's variant (octahedral: 0 equal area, 1 central)
  kOffSecond = 104,     // version 2: the chart's second length (torus: minor radius; cylinder:
                        // length; others 0)
  kOffReserved2 = 112,  // version 2: zero up to the header's CRC
  kOffHeaderCrc = 124,
};

// Version 1 knows lat-long and flat planets; version 2 adds the octahedral chart and its
// variant, the torus and the cylinder and their second length. A planet version 1 holds is written
// as version 1, so older builds keep reading it.
std::uint32_t versionFor(core::ChartShape s) {
  return s == core::ChartShape::kLatLong || s == core::ChartShape::kFlat ? 1u : 2u;
}

// The chart's name in the header (the family) and its variant.
std::pair<std::string, std::uint32_t> headerChart(core::ChartShape s) {
  if (s == core::ChartShape::kOctahedralCentral) return {"octahedral", 1};
  return {core::toString(s), 0};
}

std::uint32_t crc(std::uint32_t c, const unsigned char* p, std::size_t n) {
  // zlib's crc32 takes a uInt length: feed it in pieces.
  while (n > 0) {
    const std::size_t k = std::min<std::size_t>(n, std::size_t(1) << 30);
    c = std::uint32_t(::crc32(c, p, uInt(k)));
    p += k;
    n -= k;
  }
  return c;
}

template <class T>
void put(unsigned char* p, T x) {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char b[sizeof(T)];
  std::memcpy(b, &x, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
  std::memcpy(p, b, sizeof(T));
}

template <class T>
T get(const unsigned char* p) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
  T x;
  std::memcpy(&x, b, sizeof(T));
  return x;
}

std::uint32_t ruleCode(terrain::ErrorRule r) {
  return r == terrain::ErrorRule::kWedgie ? 0u : 1u;
}

std::size_t sampleBytes(HeightEncoding e) {
  return e == HeightEncoding::kFloat32 ? 4 : 2;
}

[[noreturn]] void failPlanet(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

// "a latlong", "an octahedral": a chart's name as a message puts it before "planet".
std::string withArticle(const std::string& chart) {
  return (chart.rfind('o', 0) == 0 ? "an " : "a ") + chart;
}

// Heights in the file's encoding (little-endian bytes) plus the scale and offset they need.
struct EncodedHeights {
  std::vector<unsigned char> bytes;  // empty: float32 on a little-endian host, write in place
  double scale = 1.0, offset = 0.0;
};

EncodedHeights encodeHeights(std::span<const float> h, HeightEncoding e) {
  EncodedHeights out;
  if (e == HeightEncoding::kFloat32) {
    if constexpr (std::endian::native != std::endian::little) {
      out.bytes.resize(h.size() * 4);
      for (std::size_t i = 0; i < h.size(); ++i) put<float>(out.bytes.data() + 4 * i, h[i]);
    }
    return out;
  }
  const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  const double minM = h.empty() ? 0.0 : *lo, maxM = h.empty() ? 0.0 : *hi;
  out.offset = minM;
  out.scale = maxM > minM ? (maxM - minM) / 65535.0 : 1.0;
  out.bytes.resize(h.size() * 2);
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double q = std::clamp(std::round((double(h[i]) - out.offset) / out.scale), 0.0, 65535.0);
    put<std::uint16_t>(out.bytes.data() + 2 * i, std::uint16_t(q));
  }
  return out;
}

std::array<unsigned char, kPlanetHeaderBytes> makeHeader(const core::Chart& chart,
                                                         HeightEncoding enc, double scale,
                                                         double offset, terrain::ErrorRule rule,
                                                         std::uint32_t metadataBytes,
                                                         std::uint64_t heightBytes,
                                                         std::uint32_t bodyCrc) {
  std::array<unsigned char, kPlanetHeaderBytes> h{};
  std::memcpy(h.data() + kOffMagic, kMagic, 8);
  const core::ChartShape shape = core::shapeOf(chart);
  const std::uint32_t version = versionFor(shape);
  put<std::uint32_t>(h.data() + kOffVersion, version);
  put<std::uint32_t>(h.data() + kOffHeaderBytes, std::uint32_t(kPlanetHeaderBytes));
  const auto [name, variant] = headerChart(shape);
  if (name.size() >= kChartNameBytes) throw std::logic_error("chart name too long: " + name);
  std::memcpy(h.data() + kOffChart, name.data(), name.size());
  put<std::uint32_t>(h.data() + kOffSide, std::uint32_t(chart.grid().side()));
  put<std::uint32_t>(h.data() + kOffEncoding, std::uint32_t(enc));
  const core::ChartDims dims = core::dimsOf(chart);
  put<double>(h.data() + kOffRadius, dims.radius);
  put<double>(h.data() + kOffDx, dims.dx);
  put<double>(h.data() + kOffDy, dims.dy);
  if (version >= 2) {
    put<std::uint32_t>(h.data() + kOffVariant, variant);
    put<double>(h.data() + kOffSecond, shape == core::ChartShape::kTorus      ? dims.minorRadius
                                       : shape == core::ChartShape::kCylinder ? dims.length
                                                                              : 0.0);
  }
  put<double>(h.data() + kOffScale, scale);
  put<double>(h.data() + kOffOffset, offset);
  put<std::uint32_t>(h.data() + kOffRule, ruleCode(rule));
  put<std::uint32_t>(h.data() + kOffMetadataBytes, metadataBytes);
  put<std::uint64_t>(h.data() + kOffHeightBytes, heightBytes);
  put<std::uint32_t>(h.data() + kOffBodyCrc, bodyCrc);
  put<std::uint32_t>(h.data() + kOffHeaderCrc, crc(0, h.data(), kOffHeaderCrc));
  return h;
}

std::string metadataText(const PlanetSaveOptions& o) {
  if (o.metadata.is_null()) return "{}";
  if (!o.metadata.is_object()) throw std::invalid_argument("planet metadata must be a JSON object");
  std::string s = o.metadata.dump();
  if (s.size() > kPlanetMaxMetadataBytes) {
    throw std::invalid_argument("planet metadata is " + std::to_string(s.size()) +
                                " bytes, more than the format's " +
                                std::to_string(kPlanetMaxMetadataBytes));
  }
  return s;
}

struct Prepared {
  std::array<unsigned char, kPlanetHeaderBytes> header;
  std::string metadata;
  EncodedHeights heights;
  const unsigned char* heightData;
  std::size_t heightBytes;
};

Prepared prepare(const core::Chart& chart, std::span<const float> heights, terrain::ErrorRule rule,
                 const PlanetSaveOptions& options) {
  if (heights.size() != chart.grid().count()) {
    throw std::invalid_argument("planet has " + std::to_string(heights.size()) +
                                " heights, its grid needs " + std::to_string(chart.grid().count()));
  }
  Prepared p;
  p.metadata = metadataText(options);
  p.heights = encodeHeights(heights, options.encoding);
  p.heightData = p.heights.bytes.empty() ? reinterpret_cast<const unsigned char*>(heights.data())
                                         : p.heights.bytes.data();
  p.heightBytes = heights.size() * sampleBytes(options.encoding);
  std::uint32_t body =
      crc(0, reinterpret_cast<const unsigned char*>(p.metadata.data()), p.metadata.size());
  body = crc(body, p.heightData, p.heightBytes);
  p.header = makeHeader(chart, options.encoding, p.heights.scale, p.heights.offset, rule,
                        std::uint32_t(p.metadata.size()), p.heightBytes, body);
  return p;
}

// The checked header fields.
struct Header {
  std::uint32_t version = 0;
  core::ChartShape shape = core::ChartShape::kLatLong;
  std::string chart;
  int side = 0;
  HeightEncoding encoding = HeightEncoding::kFloat32;
  double radius = 0, second = 0, dx = 0, dy = 0, scale = 1, offset = 0;
  terrain::ErrorRule rule = terrain::ErrorRule::kHybridExact;
  std::uint32_t metadataBytes = 0;
  std::uint64_t heightBytes = 0;
  std::uint32_t bodyCrc = 0;
  std::uint64_t fileBytes() const { return kPlanetHeaderBytes + metadataBytes + heightBytes; }
};

Header parseHeader(const unsigned char* p, std::size_t available, const std::string& name) {
  if (available == 0) failPlanet(name, "empty file (0 bytes); expected a PlanetSculpt planet file");
  if (!looksLikePlanetFile({p, std::min<std::size_t>(available, 8)})) {
    std::string what = "not a PlanetSculpt planet file (wrong magic bytes";
    if (available >= 8 && std::memcmp(p, "\x89PNG", 4) == 0) what += "; this is a PNG image";
    if (available >= 4 && (std::memcmp(p, "II*", 4) == 0 || std::memcmp(p, "MM\0*", 4) == 0)) {
      what += "; this is a TIFF image";
    }
    failPlanet(name, what + ": use `planetsculpt import` for heightmaps)");
  }
  if (available < kPlanetHeaderBytes) {
    failPlanet(name, "truncated: " + std::to_string(available) + " bytes, the header alone needs " +
                         std::to_string(kPlanetHeaderBytes));
  }
  const std::uint32_t version = get<std::uint32_t>(p + kOffVersion);
  if (version < 1 || version > kPlanetFileVersion) {
    failPlanet(name, "format version " + std::to_string(version) +
                         " is not supported (this build reads 1 to " +
                         std::to_string(kPlanetFileVersion) + ")");
  }
  const std::uint32_t headerBytes = get<std::uint32_t>(p + kOffHeaderBytes);
  if (headerBytes != kPlanetHeaderBytes) {
    failPlanet(name, "header size field is " + std::to_string(headerBytes) + ", version " +
                         std::to_string(version) + " requires " +
                         std::to_string(kPlanetHeaderBytes));
  }
  const std::uint32_t storedCrc = get<std::uint32_t>(p + kOffHeaderCrc);
  const std::uint32_t actualCrc = crc(0, p, kOffHeaderCrc);
  if (storedCrc != actualCrc && !kSkipChecksums) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "header checksum mismatch (stored CRC-32 %08x, computed %08x)",
                  storedCrc, actualCrc);
    failPlanet(name, std::string(buf) + ": the header is corrupt");
  }
  Header h;
  h.version = version;
  const char* chart = reinterpret_cast<const char*>(p + kOffChart);
  const std::size_t len = std::find(chart, chart + kChartNameBytes, '\0') - chart;
  if (len == kChartNameBytes) failPlanet(name, "chart name is not NUL-terminated");
  h.chart.assign(chart, len);
  for (std::size_t i = len; i < kChartNameBytes; ++i) {
    if (chart[i] != '\0') failPlanet(name, "chart name field has bytes after its terminating NUL");
  }
  const bool v1Chart = h.chart == "latlong" || h.chart == "flat";
  if (!v1Chart && h.chart != "octahedral" && h.chart != "torus" && h.chart != "cylinder") {
    failPlanet(name, "unknown chart '" + h.chart +
                         "' (this build knows latlong, flat, octahedral, torus and cylinder)");
  }
  if (!v1Chart && version < 2) {
    failPlanet(name, "chart '" + h.chart + "' needs format version 2, the header says " +
                         std::to_string(version));
  }
  std::uint32_t variant = 0;
  if (version >= 2) {
    variant = get<std::uint32_t>(p + kOffVariant);
    const std::uint32_t variants = h.chart == "octahedral" ? 2 : 1;
    if (variant >= variants) {
      failPlanet(name, "chart variant " + std::to_string(variant) + " is not one of the " +
                           std::to_string(variants) + " that chart '" + h.chart + "' has" +
                           (h.chart == "octahedral" ? " (0 = equal area, 1 = central)" : ""));
    }
  }
  h.shape = h.chart == "octahedral" && variant == 1 ? core::ChartShape::kOctahedralCentral
                                                    : core::chartShapeFromString(h.chart);
  const std::uint32_t side = get<std::uint32_t>(p + kOffSide);
  try {
    h.side = core::GridSize::fromSide(side).side();
  } catch (const core::InputError& e) {
    failPlanet(name, std::string("grid: ") + e.what());
  }
  const std::uint32_t enc = get<std::uint32_t>(p + kOffEncoding);
  if (enc != std::uint32_t(HeightEncoding::kFloat32) &&
      enc != std::uint32_t(HeightEncoding::kUint16)) {
    failPlanet(name,
               "unknown height encoding " + std::to_string(enc) + " (1 = float32, 2 = uint16)");
  }
  h.encoding = HeightEncoding(enc);
  h.radius = get<double>(p + kOffRadius);
  h.dx = get<double>(p + kOffDx);
  h.dy = get<double>(p + kOffDy);
  if (version >= 2) h.second = get<double>(p + kOffSecond);
  const bool torus = h.shape == core::ChartShape::kTorus,
             tube = h.shape == core::ChartShape::kCylinder;
  if (h.second != 0 && !torus && !tube)
    failPlanet(name, withArticle(h.chart) + " planet must store 0 in the second length field");
  if (torus || tube) {
    if (!std::isfinite(h.radius) || h.radius <= 0)
      failPlanet(name, "radius " + core::exactNumber(h.radius) + " m must be positive and finite");
    if (!std::isfinite(h.second) || h.second <= 0)
      failPlanet(name, std::string(torus ? "minor radius " : "length ") +
                           core::exactNumber(h.second) + " m must be positive and finite");
    if (torus && h.second >= h.radius)
      failPlanet(name, "minor radius " + core::exactNumber(h.second) +
                           " m must be below the major radius " + core::exactNumber(h.radius) +
                           " m");
    if (h.dx != 0 || h.dy != 0)
      failPlanet(name, withArticle(h.chart) + " planet must store 0 in the flat spacing fields");
  } else if (core::isSphere(h.shape)) {
    if (!std::isfinite(h.radius) || h.radius <= 0) {
      failPlanet(name, "radius " + core::exactNumber(h.radius) + " m must be positive and finite");
    }
    if (h.dx != 0 || h.dy != 0)
      failPlanet(name, withArticle(h.chart) + " planet must store 0 in the flat spacing fields");
  } else {
    if (!std::isfinite(h.dx) || h.dx <= 0 || !std::isfinite(h.dy) || h.dy <= 0) {
      failPlanet(name, "flat grid spacing " + core::exactNumber(h.dx) + " x " +
                           core::exactNumber(h.dy) + " m must be positive and finite");
    }
    if (h.radius != 0) failPlanet(name, "a flat planet must store radius 0");
  }
  h.scale = get<double>(p + kOffScale);
  h.offset = get<double>(p + kOffOffset);
  if (!std::isfinite(h.scale) || h.scale <= 0) {
    failPlanet(name, "height scale " + core::exactNumber(h.scale) + " must be positive and finite");
  }
  if (!std::isfinite(h.offset))
    failPlanet(name, "height offset " + core::exactNumber(h.offset) + " must be finite");
  const std::uint32_t rule = get<std::uint32_t>(p + kOffRule);
  if (rule > 1)
    failPlanet(name,
               "unknown error rule " + std::to_string(rule) + " (0 = wedgie, 1 = hybrid-exact)");
  h.rule = rule == 0 ? terrain::ErrorRule::kWedgie : terrain::ErrorRule::kHybridExact;
  h.metadataBytes = get<std::uint32_t>(p + kOffMetadataBytes);
  if (h.metadataBytes > kPlanetMaxMetadataBytes) {
    failPlanet(name, "metadata block of " + std::to_string(h.metadataBytes) +
                         " bytes exceeds the limit of " + std::to_string(kPlanetMaxMetadataBytes));
  }
  h.heightBytes = get<std::uint64_t>(p + kOffHeightBytes);
  const std::uint64_t want =
      std::uint64_t(h.side) * std::uint64_t(h.side) * sampleBytes(h.encoding);
  if (h.heightBytes != want) {
    failPlanet(name, "height block is " + std::to_string(h.heightBytes) + " bytes, a " +
                         std::to_string(h.side) + "x" + std::to_string(h.side) + " grid of " +
                         toString(h.encoding) + " needs " + std::to_string(want));
  }
  h.bodyCrc = get<std::uint32_t>(p + kOffBodyCrc);
  for (std::size_t i = version >= 2 ? kOffReserved2 : kOffReserved; i < kOffHeaderCrc; ++i) {
    if (p[i] != 0) failPlanet(name, "reserved header byte " + std::to_string(i) + " is not zero");
  }
  return h;
}

void checkSize(const Header& h, std::uint64_t actual, const std::string& name) {
  if (actual < h.fileBytes()) {
    failPlanet(name, "truncated: " + std::to_string(actual) + " bytes, the header announces " +
                         std::to_string(h.fileBytes()) + " (" +
                         std::to_string(h.fileBytes() - actual) + " missing)");
  }
  if (actual > h.fileBytes()) {
    failPlanet(name, std::to_string(actual - h.fileBytes()) +
                         " unexpected bytes after the end of the planet (" +
                         std::to_string(h.fileBytes()) + " bytes announced)");
  }
}

// Checks the body (metadata + heights) of a file whose header is `h`.
PlanetData parseBody(const Header& h, const unsigned char* body, const std::string& name) {
  const std::uint32_t bodyCrc =
      crc(crc(0, body, h.metadataBytes), body + h.metadataBytes, h.heightBytes);
  if (bodyCrc != h.bodyCrc && !kSkipChecksums) {
    char buf[128];
    std::snprintf(
        buf, sizeof buf,
        "checksum mismatch: stored CRC-32 %08x, computed %08x over the metadata and heights",
        h.bodyCrc, bodyCrc);
    failPlanet(name, std::string(buf) + ": the file is corrupt");
  }
  PlanetData d;
  if (h.metadataBytes > 0) {
    const std::string text(reinterpret_cast<const char*>(body), h.metadataBytes);
    nlohmann::json meta = nlohmann::json::parse(text, nullptr, false);
    if (meta.is_discarded() || !meta.is_object())
      failPlanet(name, "metadata block is not a JSON object");
    d.metadata = std::move(meta);
  }
  const core::GridSize g = core::GridSize::fromSide(h.side);
  core::ChartDims dims;
  dims.radius = h.radius;
  dims.minorRadius = h.shape == core::ChartShape::kTorus ? h.second : 0.0;
  dims.length = h.shape == core::ChartShape::kCylinder ? h.second : 0.0;
  dims.dx = h.dx;
  dims.dy = h.dy;
  try {
    d.chart = core::makeChart(h.shape, g, dims);
  } catch (const core::InputError& e) {
    failPlanet(name, e.what());
  }
  d.rule = h.rule;
  d.encoding = h.encoding;
  d.heightScale = h.scale;
  d.heightOffset = h.offset;
  d.heights.resize(g.count());
  const unsigned char* src = body + h.metadataBytes;
  if (h.encoding == HeightEncoding::kFloat32) {
    if (h.scale == 1.0 && h.offset == 0.0) {
      for (std::size_t i = 0; i < d.heights.size(); ++i) d.heights[i] = get<float>(src + 4 * i);
    } else {
      for (std::size_t i = 0; i < d.heights.size(); ++i) {
        d.heights[i] = float(double(get<float>(src + 4 * i)) * h.scale + h.offset);
      }
    }
  } else {
    for (std::size_t i = 0; i < d.heights.size(); ++i) {
      d.heights[i] = float(double(get<std::uint16_t>(src + 2 * i)) * h.scale + h.offset);
    }
  }
  try {
    terrain::Terrain::validateHeights(*d.chart, d.heights);
  } catch (const core::InputError& e) {
    failPlanet(name, e.what());
  }
  return d;
}

}  // namespace

constexpr core::NameTable<HeightEncoding, 4> kHeightEncodings{
    "height encoding",
    {{{HeightEncoding::kFloat32, "f32"},
      {HeightEncoding::kUint16, "u16"},
      {HeightEncoding::kFloat32, "float32"},
      {HeightEncoding::kUint16, "uint16"}}}};

std::string toString(HeightEncoding e) {
  return kHeightEncodings.nameOf(e);
}

HeightEncoding heightEncodingFromString(const std::string& s) {
  return kHeightEncodings.parse(s);
}

bool looksLikePlanetFile(std::span<const unsigned char> b) {
  return b.size() >= 8 && std::memcmp(b.data(), kMagic, 8) == 0;
}

std::vector<unsigned char> encodePlanet(const core::Chart& chart, std::span<const float> heights,
                                        terrain::ErrorRule rule, const PlanetSaveOptions& options) {
  const Prepared p = prepare(chart, heights, rule, options);
  // Sized once and filled with memcpy (g++ 12 -O3 raises a false -Warray-bounds on the
  // iterator-range constructor from the std::array).
  std::vector<unsigned char> out(kPlanetHeaderBytes + p.metadata.size() + p.heightBytes);
  std::memcpy(out.data(), p.header.data(), kPlanetHeaderBytes);
  if (!p.metadata.empty()) {
    std::memcpy(out.data() + kPlanetHeaderBytes, p.metadata.data(), p.metadata.size());
  }
  if (p.heightBytes > 0) {
    std::memcpy(out.data() + kPlanetHeaderBytes + p.metadata.size(), p.heightData, p.heightBytes);
  }
  return out;
}

PlanetData parsePlanet(std::span<const unsigned char> bytes, const std::string& name) {
  const Header h = parseHeader(bytes.data(), bytes.size(), name);
  checkSize(h, bytes.size(), name);
  return parseBody(h, bytes.data() + kPlanetHeaderBytes, name);
}

PlanetData readPlanetFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) failPlanet(name, "no such file");
  if (std::filesystem::is_directory(status)) failPlanet(name, "is a directory, not a planet file");
  std::ifstream f(path, std::ios::binary);
  if (!f) failPlanet(name, "cannot open for reading");
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) failPlanet(name, "cannot read its size: " + ec.message());
  std::array<unsigned char, kPlanetHeaderBytes> head{};
  const std::size_t first = std::size_t(std::min<std::uint64_t>(size, kPlanetHeaderBytes));
  f.read(reinterpret_cast<char*>(head.data()), std::streamsize(first));
  if (std::size_t(f.gcount()) != first) failPlanet(name, "read error in the header");
  const Header h = parseHeader(head.data(), first, name);
  checkSize(h, size, name);
  std::vector<unsigned char> body(std::size_t(h.metadataBytes + h.heightBytes));
  f.read(reinterpret_cast<char*>(body.data()), std::streamsize(body.size()));
  if (std::size_t(f.gcount()) != body.size()) {
    failPlanet(name, "read error: got " + std::to_string(f.gcount()) + " of " +
                         std::to_string(body.size()) +
                         " body bytes (was the file truncated while reading?)");
  }
  return parseBody(h, body.data(), name);
}

std::unique_ptr<terrain::Terrain> loadPlanet(const std::filesystem::path& path) {
  PlanetData d = readPlanetFile(path);
  try {
    return std::make_unique<terrain::Terrain>(d.chart, std::move(d.heights), d.rule);
  } catch (const core::InputError& e) {
    failPlanet(path.string(), e.what());
  }
}

PlanetPrologue planetPrologue(const core::Chart& chart, terrain::ErrorRule rule,
                              std::uint32_t heightsCrc, const PlanetSaveOptions& options) {
  if (options.encoding != HeightEncoding::kFloat32)
    throw std::invalid_argument("planetPrologue: float32 heights only");
  PlanetPrologue p;
  p.metadata = metadataText(options);
  const std::uint64_t heightBytes = chart.grid().count() * sizeof(float);
  const std::uint32_t body = std::uint32_t(::crc32_combine(
      crc(0, reinterpret_cast<const unsigned char*>(p.metadata.data()), p.metadata.size()),
      heightsCrc, z_off_t(heightBytes)));
  p.header = makeHeader(chart, HeightEncoding::kFloat32, 1.0, 0.0, rule,
                        std::uint32_t(p.metadata.size()), heightBytes, body);
  return p;
}

void savePlanet(const core::Chart& chart, std::span<const float> heights, terrain::ErrorRule rule,
                const std::filesystem::path& path, const PlanetSaveOptions& options) {
  const Prepared p = prepare(chart, heights, rule, options);
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error("cannot create " + tmp.string() + " to save " + path.string());
    f.write(reinterpret_cast<const char*>(p.header.data()), std::streamsize(p.header.size()));
    f.write(p.metadata.data(), std::streamsize(p.metadata.size()));
    // Large writes in pieces, so a stream never sees a count beyond its streamsize.
    for (std::size_t at = 0; at < p.heightBytes && f;) {
      const std::size_t k = std::min<std::size_t>(p.heightBytes - at, std::size_t(64) << 20);
      f.write(reinterpret_cast<const char*>(p.heightData + at), std::streamsize(k));
      at += k;
    }
    f.close();
    if (!f) throw std::runtime_error("cannot write " + path.string() + " (disk full?)");
  });
}

void savePlanet(const terrain::Terrain& terrain, const std::filesystem::path& path,
                const PlanetSaveOptions& options) {
  savePlanet(terrain.chart(), terrain.heights(), terrain.bounds().rule(), path, options);
}

}  // namespace ps::io
