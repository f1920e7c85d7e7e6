#pragma once
// Decoding a user's heightmap file into raw sample values (before scale, offset, no-data
// filling and resampling; see io/heightmap_import.hpp). Every parser here checks dimensions
// before it allocates and throws core::InputError "<file>: <what is wrong>".
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ps::io {

// Images larger than this are refused before any pixel is decoded (1 GiB of float samples).
inline constexpr std::uint64_t kMaxImagePixels = std::uint64_t(1) << 28;
inline constexpr std::uint64_t kMaxImageSide = std::uint64_t(1) << 20;

// A raster's georeferencing (GDAL's north-up geotransform and CRS), when present.
struct GeoReference {
  double pixelScaleX = 0, pixelScaleY = 0;  // CRS units per pixel
  double originX = 0, originY = 0;          // CRS coordinates of the raster's top-left corner
  bool geographic = false;                  // a geographic CRS (degrees)
  std::optional<double> sphereRadius;       // the CRS's ellipsoid when its axes are equal (metres)
};

struct HeightImage {
  int width = 0, height = 0;
  std::vector<float> values;  // samples as stored, row-major, row 0 at the top
  std::string kind;           // e.g. "16-bit grey PNG", "int16 TIFF", "float32 raw"
  // Declared no-data value in stored units (NaN: NaN marks no data) and where it came from.
  std::optional<double> noData;
  std::string noDataSource;
  // The file's own scale and offset (metres = value * scale + offset), when it declares them.
  std::optional<double> fileScale, fileOffset;
  // A PlanetSculpt 16-bit PNG's tEXt chunks: the metres that 0 and 65535 stand for.
  std::optional<double> value0Metres, value65535Metres;
  // Longitude of the western edge, when a sidecar says so.
  std::optional<double> column0LongitudeDeg;
  // "equirectangular", "flat", "torus" or "cylinder" when the file says which (our own exports
  // do).
  std::string projection;
  // Flat exports' sidecars: metres between pixel centres.
  std::optional<double> pixelSpacingX, pixelSpacingY;
  std::optional<GeoReference> geo;
  // The sphere's radius, when the file names one (a GeoTIFF's user-defined ellipsoid with equal
  // axes, a raw sidecar's "radius_m"; a torus's major radius, a cylinder's radius).
  std::optional<double> radiusMetres;
  // A raw sidecar's "minor_radius_m" (a torus) and "length_m" (a cylinder).
  std::optional<double> minorRadiusMetres, lengthMetres;

  std::uint64_t pixelCount() const { return std::uint64_t(width) * std::uint64_t(height); }
  float at(int x, int y) const {
    return values[std::size_t(y) * std::size_t(width) + std::size_t(x)];
  }
};

enum class ImageFormat { kUnknown, kPng, kTiff, kPlanet };

// How a PNG's pixels hold heights. kStored: one grey sample per pixel, the value as stored.
// Web DEM tiles pack a height into the three 8-bit colour channels:
//   kTerrainRgb (Mapbox Terrain-RGB): metres = -10000 + (R * 65536 + G * 256 + B) * 0.1
//   kTerrarium (Mapzen / AWS Terrain Tiles): metres = R * 256 + G + B / 256 - 32768
enum class PngHeightEncoding { kStored, kTerrainRgb, kTerrarium };
std::string toString(PngHeightEncoding e);
PngHeightEncoding pngHeightEncodingFromString(
    const std::string& s);  // "stored" | "terrain-rgb" | "terrarium"
ImageFormat sniffFormat(std::span<const unsigned char> firstBytes);

// PNG (8/16-bit grey, libpng) or TIFF (one band of integers or floats, through GDAL's GTiff
// driver with its georeferencing, no-data, scale and offset), chosen by the magic bytes. Images of
// more than maxPixels (at most kMaxImagePixels) are refused before any buffer is allocated for
// them.
// An RGB encoding applies to PNGs only (other files are refused with it).
HeightImage decodeHeightImage(std::span<const unsigned char> bytes, const std::string& name,
                              std::uint64_t maxPixels = kMaxImagePixels,
                              PngHeightEncoding encoding = PngHeightEncoding::kStored);

// Raw little-endian float32 samples described by a sidecar JSON (what `export --format raw`
// writes next to the data as `<file>.json`).
struct RawSidecar {
  int width = 0, height = 0;
  std::optional<double> noData;  // "nodata": number or "nan"
  std::optional<double> column0LongitudeDeg;
  std::string projection;
  std::optional<double> pixelSpacingX, pixelSpacingY;
  std::optional<double> radiusMetres, minorRadiusMetres, lengthMetres;
};
RawSidecar parseRawSidecar(std::string_view json, const std::string& name);
HeightImage decodeRaw(std::span<const unsigned char> bytes, const RawSidecar& sidecar,
                      const std::string& name);

// Reads a file: PNG by its magic, raw float32 when `<file>.json` exists, anything else (TIFF,
// PDS3, SRTM .hgt, an ESRI grid's folder, ...) through GDAL (io/gdal_raster.hpp).
HeightImage readHeightImage(const std::filesystem::path& path,
                            PngHeightEncoding encoding = PngHeightEncoding::kStored);

// The whole file, refusing more than maxBytes (named in the error).
std::vector<unsigned char> readFileBytes(const std::filesystem::path& path,
                                         std::uint64_t maxBytes = std::uint64_t(8) << 30);

}  // namespace ps::io
