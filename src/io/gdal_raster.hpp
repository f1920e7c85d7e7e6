#pragma once
// Rasters through GDAL: what `import` reads beside its own PNG and raw formats (GeoTIFF with any
// CRS, PDS3 .IMG + .LBL, SRTM .hgt, ESRI grids, netCDF, anything GDAL opens), with the file's
// georeferencing, scale, offset, no-data and, for a body described by a sphere (a planetary
// label's radius), its radius; and the GeoTIFFs `export` writes, with their CRS.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "io/height_image.hpp"

namespace ps::io {

struct Raster;

// The first band of a raster GDAL opens from `path` (sibling files such as a PDS3 label next to
// its .IMG are found by GDAL). Refused with core::InputError naming the file: what GDAL cannot
// open, more than one band, complex samples, rotated georeferencing, more than maxPixels, and
// files too small for the uncompressed samples their header declares. `tiff`: the file starts
// as a TIFF does (a failure to open is then a corrupt TIFF).
HeightImage readGdalRaster(const std::filesystem::path& path,
                           std::uint64_t maxPixels = kMaxImagePixels, bool tiff = false);
// The same from bytes in memory (a TIFF: only GDAL's GTiff driver is tried).
HeightImage decodeGdalTiff(std::span<const unsigned char> bytes, const std::string& name,
                           std::uint64_t maxPixels = kMaxImagePixels);

// One-band float32 GeoTIFF, atomically: a lat-long raster on a geographic CRS of a sphere of the
// planet's radius (degrees, -180..180 x -90..90, pixel is area); a flat one in metres with no
// CRS (pixel is point, pixel centres at (x dx, (height - 1 - y) dy)).
void writeGdalGeoTiff(const Raster& raster, const std::filesystem::path& path,
                      const std::string& description);

}  // namespace ps::io
