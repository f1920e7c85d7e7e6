#pragma once
#include <filesystem>
#include <opencv2/core.hpp>
#include <vector>

#include "io/resample.hpp"
#include "terrain/terrain.hpp"

namespace ps::io {

// An equirectangular raster resampled from the planet: row 0 is the north edge, column 0 the
// western edge (longitude -180 deg); pixel centres sit at half-pixel offsets, so no pixel lies
// exactly on a pole and the seam is sampled from both sides alike.
struct Raster {
  int width = 0, height = 0;
  std::vector<float> metres;  // row-major

  // How pixels map onto the planet (written to sidecars, PNG text chunks and GeoTIFF tags).
  enum class Layout {
    kEquirectangular,  // pixel-is-area, row 0 north, column 0 at -180 deg (resampleEquirectangular)
    kFlat,             // pixel-is-point over a flat chart, row 0 at v = m (resampleFlat)
    kTorus,            // a torus's (u, v) grid, both ways periodic (resampleTube)
    kCylinder,         // a cylinder's (u, v) grid, u periodic, rows 0 and height-1 its ends
  };
  Layout layout = Layout::kEquirectangular;
  double radiusMetres = 0;                   // equirectangular: the sphere (0: unknown)
  double pixelWidthM = 0, pixelHeightM = 0;  // flat: metres between pixel centres
  double minorRadiusM = 0, lengthM = 0;      // torus, cylinder (radiusMetres: the major/tube)
};

// Bilinear in (u, v) between grid vertices; across the seam the grid wraps.
Raster resampleEquirectangular(const terrain::Terrain& terrain, int width, int height,
                               Interpolation how = Interpolation::kCubic);

// A flat chart's heights as a width x height image whose corner pixels sit on the grid's corner
// vertices (pixel-is-point); at the grid's own size (side x side) every pixel is one vertex,
// exactly. Bilinear in between. Row 0 is the v = m edge. Throws std::invalid_argument unless
// the terrain's chart is a core::FlatChart.
Raster resampleFlat(const terrain::Terrain& terrain, int width, int height,
                    Interpolation how = Interpolation::kCubic);

// A torus's or a cylinder's heights as its own (u, v) grid: column x at u = x m / width, round the
// axis (u wraps); a torus's row y at v = (height - 1 - y) m / height (v wraps too), a cylinder's
// at v = (height - 1 - y) m / (height - 1) (rows 0 and height - 1 are its ends, v = m and 0).
// At the grid's own size (m x m, a cylinder m x (m + 1)) every pixel is one vertex, exactly, and
// io::importHeightmap takes the image back onto the same grid bit for bit. Throws
// std::invalid_argument for another chart.
Raster resampleTube(const terrain::Terrain& terrain, int width, int height,
                    Interpolation how = Interpolation::kCubic);

// 32-bit float TIFF (one band, metres; strips, uncompressed) readable by GDAL/QGIS: for an
// equirectangular raster with a known radius it carries GeoTIFF tags (geographic degrees on a
// sphere of that radius, pixel-is-area, -180..180 x -90..90). Atomic.
void writeHeightTiff32(const Raster& raster, const std::filesystem::path& path);

// Raw little-endian float32 metres, row-major, and the sidecar `<file>.json` that
// io::parseRawSidecar reads ("format": "float32le", width, height, projection, ...). Atomic.
void writeHeightRaw32(const Raster& raster, const std::filesystem::path& path);

// 16-bit grey PNG; 0 and 65535 stand for the raster's min and max metres, recorded in the
// PNG's text chunk (keys "planetsculpt:min_m", "planetsculpt:max_m") and in a sidecar
// `<file>.json`. Atomic.
void writeHeightPng16(const Raster& raster, const std::filesystem::path& path);

// Colour preview: hypsometric tint with hill shading (8-bit RGB PNG). Atomic.
void writeReliefPreview(const Raster& raster, double metresPerPixel,
                        const std::filesystem::path& path);
// The colour ramp of the previews and the renderer: metres -> BGR in [0, 255].
cv::Vec3f hypsometricTint(double metres);
// The same picture as an 8-bit BGR image.
cv::Mat reliefImage(const Raster& raster, double metresPerPixel);
// Any image as a PNG, written atomically (temporary file + rename).
void writePngAtomically(const cv::Mat& image, const std::filesystem::path& path);

}  // namespace ps::io
