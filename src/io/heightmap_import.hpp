#pragma once
// `planetsculpt import`: a user's heightmap -> a planet (chart + heights on a (2^n+1)^2 grid).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/chart_factory.hpp"
#include "io/height_image.hpp"
#include "io/planet_file.hpp"
#include "io/resample.hpp"

namespace ps::io {

// The chart a heightmap is imported onto: a sphere (latlong, octahedral: from an equirectangular
// image), flat (a terrain tile), or a torus or cylinder (from an image of its own (u, v) grid, as
// io::resampleTube writes it: periodic round the axis, a torus's rows too).
using ChartKind = core::ChartShape;
enum class NoDataPolicy { kFill, kRefuse };

ChartKind chartKindFromString(const std::string& s);        // core::kChartShapeNames; InputError
NoDataPolicy noDataPolicyFromString(const std::string& s);  // "fill" | "refuse"; InputError
double noDataValueFromString(const std::string& s);         // a number or "nan"; InputError

inline constexpr double kDefaultImportRadius = 6372790.0;  // paper 003's Earth

struct ImportOptions {
  ChartKind chart = ChartKind::kLatLong;
  // a sphere (latlong, octahedral): metres. Unset: the file's (a GeoTIFF's sphere, a sidecar's
  // radius_m), else kDefaultImportRadius.
  std::optional<double> radius;
  // torus: the tube's radius (required); cylinder: its length (required); metres. The radius
  // above is then the torus's major radius, the cylinder's radius (required for both).
  std::optional<double> minorRadius, length;
  // metres = value * scale + offset. Unset: a PlanetSculpt 16-bit PNG's own range, the file's
  // own scale and offset (GDAL's), else 1 and 0.
  std::optional<double> scale, offset;
  long long gridSide = 0;  // 2^n+1; 0: defaultGridSide
  NoDataPolicy noData = NoDataPolicy::kFill;
  std::optional<double> noDataValue;  // declares (or overrides) the no-data value; NaN allowed
  // latlong: longitude of the image's western edge (default: the file's, else -180).
  std::optional<double> westLongitudeDeg;
  // flat: metres between pixel centres (default: the file's or the GeoTIFF's, else 1).
  std::optional<double> spacing;
  terrain::ErrorRule rule = terrain::ErrorRule::kHybridExact;
  // How the image is sampled at the grid's vertices (after area-averaging where it is finer).
  Interpolation interpolation = Interpolation::kCubic;
  // PNGs: grey samples as stored, or a web DEM tile's RGB-packed heights.
  PngHeightEncoding encoding = PngHeightEncoding::kStored;
};

struct ImportResult {
  PlanetData planet;
  std::vector<std::string> notes;  // what the user must be told (scale chosen, holes filled, ...)
  std::size_t noDataPixels = 0;
};

// Applies no-data, scale/offset and resampling to a decoded image. `name` is used in errors.
ImportResult importHeightImage(HeightImage image, const ImportOptions& options,
                               const std::string& name);
ImportResult importHeightmap(const std::filesystem::path& path, const ImportOptions& options);

// A flat heightmap's own samples in metres (no-data filled, scale and offset applied, nothing
// resampled), for meshers that keep every sample (the TIN export). Rows run south to north:
// heights[j * width + i], j = 0 the image's bottom row, as a flat chart's v. `name` in errors.
struct HeightSamples {
  int width = 0, height = 0;
  std::vector<float> heights;
  double dx = 1, dy = 1;  // metres between samples
  std::vector<std::string> notes;
  std::size_t noDataPixels = 0;
  std::optional<GeoReference> geo;  // the file's georeferencing, when it has one
};
HeightSamples heightSamples(HeightImage image, const ImportOptions& options,
                            const std::string& name);

// The default grid side for an image (see ImportOptions::gridSide).
long long defaultGridSide(ChartKind chart, int width, int height);

}  // namespace ps::io
