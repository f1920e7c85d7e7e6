#include "io/gdal_raster.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/input_error.hpp"
#include "io/atomic_file.hpp"
#include "io/heightmap_export.hpp"

namespace ps::io {

namespace {

[[noreturn]] void failRaster(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

void registerDrivers() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

// GDAL's own complaint about the last call on this thread ("" when it said nothing).
std::string gdalMessage() {
  const char* m = CPLGetLastErrorMsg();
  return m && *m ? std::string(" (GDAL: ") + m + ")" : std::string();
}

// GDAL reports errors through CPLError; while a reader runs they are kept quiet (the caller's
// InputError names the file and carries GDAL's message).
struct QuietErrors {
  QuietErrors() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietErrors() { CPLPopErrorHandler(); }
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;
};

struct DatasetCloser {
  void operator()(void* ds) const {
    if (ds) GDALClose(ds);
  }
};
using Dataset = std::unique_ptr<void, DatasetCloser>;

std::string rasterDims(std::uint64_t w, std::uint64_t h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

void checkRasterDims(std::uint64_t w, std::uint64_t h, const std::string& name,
                     std::uint64_t maxPixels) {
  if (w == 0 || h == 0) failRaster(name, "image has no pixels (" + rasterDims(w, h) + ")");
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > maxPixels) {
    failRaster(name, "image is " + rasterDims(w, h) + " pixels (" + std::to_string(w * h) +
                         "), more than this build accepts (" + std::to_string(maxPixels) +
                         " pixels, " + std::to_string(kMaxImageSide) +
                         " per side): crop or downsample it first");
  }
}

// GDAL's type names as this project names samples ("int16", "float32").
std::string typeName(GDALDataType t) {
  switch (t) {
    case GDT_Byte:
      return "uint8";
    case GDT_UInt16:
      return "uint16";
    case GDT_Int16:
      return "int16";
    case GDT_UInt32:
      return "uint32";
    case GDT_Int32:
      return "int32";
    case GDT_Float32:
      return "float32";
    case GDT_Float64:
      return "float64";
    default:
      return GDALGetDataTypeName(t) ? GDALGetDataTypeName(t) : "unknown";
  }
}

// The raster's georeferencing from its geotransform (corner-based; GDAL has already moved a
// pixel-is-point tie point to the corner) and CRS.
std::optional<GeoReference> georeference(GDALDatasetH ds, const std::string& name) {
  double gt[6];
  if (GDALGetGeoTransform(ds, gt) != CE_None) return std::nullopt;
  if (gt[2] != 0.0 || gt[4] != 0.0)
    failRaster(name,
               "rotated or sheared georeferencing is not supported (warp it north-up first, e.g. "
               "gdalwarp)");
  GeoReference g;
  g.originX = gt[0];
  g.originY = gt[3];
  g.pixelScaleX = gt[1];
  g.pixelScaleY = -gt[5];
  for (double x : {g.pixelScaleX, g.pixelScaleY, g.originX, g.originY})
    if (!std::isfinite(x)) return std::nullopt;
  if (g.pixelScaleX <= 0 || g.pixelScaleY <= 0) return std::nullopt;
  if (OGRSpatialReferenceH srs = GDALGetSpatialRef(ds)) {
    g.geographic = OSRIsGeographic(srs) != 0;
    OGRErr e1 = OGRERR_NONE, e2 = OGRERR_NONE;
    const double a = OSRGetSemiMajor(srs, &e1), b = OSRGetSemiMinor(srs, &e2);
    if (e1 == OGRERR_NONE && e2 == OGRERR_NONE && a == b && std::isfinite(a) && a > 0)
      g.sphereRadius = a;
    // Equirectangular metres on a sphere with the equator as standard parallel (how planetary
    // DEMs such as PDS3 "SIMPLE CYLINDRICAL" products come) are degrees scaled by R pi / 180.
    const char* method = OSRGetAttrValue(srs, "PROJECTION", 0);
    if (!g.geographic && g.sphereRadius && method && std::string(method) == "Equirectangular" &&
        OSRGetProjParm(srs, SRS_PP_STANDARD_PARALLEL_1, 0.0, nullptr) == 0.0) {
      const double metresPerDegree = *g.sphereRadius * M_PI / 180.0;
      const double centre = OSRGetProjParm(srs, SRS_PP_CENTRAL_MERIDIAN, 0.0, nullptr);
      g.originX = g.originX / metresPerDegree + centre;
      g.originY = g.originY / metresPerDegree;
      g.pixelScaleX /= metresPerDegree;
      g.pixelScaleY /= metresPerDegree;
      g.geographic = true;
    }
  }
  return g;
}

// Everything but the bytes: the opened dataset's first band into an image.
HeightImage readDataset(GDALDatasetH ds, const std::string& name, std::uint64_t maxPixels,
                        std::uint64_t fileBytes) {
  const int w = GDALGetRasterXSize(ds), h = GDALGetRasterYSize(ds);
  checkRasterDims(std::uint64_t(std::max(w, 0)), std::uint64_t(std::max(h, 0)), name, maxPixels);
  const int bands = GDALGetRasterCount(ds);
  if (bands != 1)
    failRaster(
        name, "has " + std::to_string(bands) + " bands: a heightmap must have one (a single band)");
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  const GDALDataType type = GDALGetRasterDataType(band);
  if (GDALDataTypeIsComplex(type) || type == GDT_Unknown)
    failRaster(name, "sample type " + typeName(type) + " is not supported: use integers or floats");
  const std::string driver = GDALGetDriverShortName(GDALGetDatasetDriver(ds));
  HeightImage img;
  img.kind = typeName(type) + " " + (driver == "GTiff" ? std::string("TIFF") : driver);
  img.width = w;
  img.height = h;
  // Refusals before anything is allocated for pixels that cannot exist.
  const std::uint64_t sampleBytes = std::uint64_t(GDALGetDataTypeSizeBytes(type));
  const char* compression = GDALGetMetadataItem(ds, "COMPRESSION", "IMAGE_STRUCTURE");
  if (driver == "GTiff" && !compression && fileBytes > 0 &&
      std::uint64_t(w) * std::uint64_t(h) * sampleBytes > fileBytes) {
    failRaster(name, "truncated TIFF: " + rasterDims(std::uint64_t(w), std::uint64_t(h)) +
                         " uncompressed " + typeName(type) + " samples need " +
                         std::to_string(std::uint64_t(w) * std::uint64_t(h) * sampleBytes) +
                         " bytes, the file has " + std::to_string(fileBytes));
  }
  int bw = 0, bh = 0;
  GDALGetBlockSize(band, &bw, &bh);
  const auto roundUp16 = [](std::uint64_t x) { return (x + 15) / 16 * 16; };
  if (driver == "GTiff" && bh > 1 &&
      (std::uint64_t(bw) > roundUp16(std::uint64_t(w)) ||
       std::uint64_t(bh) > roundUp16(std::uint64_t(h)))) {
    failRaster(name, "TIFF tile is " + rasterDims(std::uint64_t(bw), std::uint64_t(bh)) +
                         " pixels, larger than the " +
                         rasterDims(std::uint64_t(w), std::uint64_t(h)) + " image");
  }
  int has = 0;
  const double noData = GDALGetRasterNoDataValue(band, &has);
  if (has) {
    img.noData = noData;
    img.noDataSource = driver == "GTiff" ? "GDAL_NODATA tag" : driver + " no-data value";
  }
  int hasScale = 0, hasOffset = 0;
  const double scale = GDALGetRasterScale(band, &hasScale),
               offset = GDALGetRasterOffset(band, &hasOffset);
  if ((hasScale && scale != 1.0) || (hasOffset && offset != 0.0)) {
    img.fileScale = hasScale ? scale : 1.0;
    img.fileOffset = hasOffset ? offset : 0.0;
  }
  img.geo = georeference(ds, name);
  if (img.geo && img.geo->sphereRadius) img.radiusMetres = img.geo->sphereRadius;
  img.values.resize(img.pixelCount());
  if (GDALRasterIO(band, GF_Read, 0, 0, w, h, img.values.data(), w, h, GDT_Float32, 0, 0) !=
      CE_None)
    failRaster(name, "corrupt or truncated " + (driver == "GTiff" ? std::string("TIFF") : driver) +
                         ": the samples cannot be read" + gdalMessage());
  return img;
}

}  // namespace

HeightImage readGdalRaster(const std::filesystem::path& path, std::uint64_t maxPixels, bool tiff) {
  registerDrivers();
  const std::string name = path.string();
  QuietErrors quiet;
  Dataset ds(
      GDALOpenEx(name.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds)
    failRaster(name,
               (tiff ? "corrupt or truncated TIFF" : "not a raster GDAL can open") + gdalMessage());
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return readDataset(ds.get(), name, std::min(maxPixels, kMaxImagePixels), ec ? 0 : size);
}

HeightImage decodeGdalTiff(std::span<const unsigned char> bytes, const std::string& name,
                           std::uint64_t maxPixels) {
  registerDrivers();
  static std::atomic<unsigned> counter{0};
  const std::string mem = "/vsimem/planetsculpt_" +
                          std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id())) +
                          "_" + std::to_string(counter++) + ".tif";
  QuietErrors quiet;
  VSILFILE* f = VSIFileFromMemBuffer(mem.c_str(), const_cast<GByte*>(bytes.data()),
                                     vsi_l_offset(bytes.size()), FALSE);
  if (!f) failRaster(name, "cannot hand the TIFF to GDAL" + gdalMessage());
  VSIFCloseL(f);
  struct Unlink {
    std::string path;
    ~Unlink() { VSIUnlink(path.c_str()); }
  } unlink{mem};
  const char* const drivers[] = {"GTiff", nullptr};
  Dataset ds(GDALOpenEx(mem.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, drivers, nullptr, nullptr));
  if (!ds) failRaster(name, "corrupt or truncated TIFF" + gdalMessage());
  return readDataset(ds.get(), name, std::min(maxPixels, kMaxImagePixels), bytes.size());
}

void writeGdalGeoTiff(const Raster& raster, const std::filesystem::path& path,
                      const std::string& description) {
  registerDrivers();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  if (!driver) throw std::runtime_error("GDAL has no GTiff driver");
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    QuietErrors quiet;
    Dataset ds(
        GDALCreate(driver, tmp.c_str(), raster.width, raster.height, 1, GDT_Float32, nullptr));
    if (!ds) throw std::runtime_error("cannot create " + tmp.string() + gdalMessage());
    GDALSetMetadataItem(ds.get(), "TIFFTAG_SOFTWARE", "PlanetSculpt", nullptr);
    GDALSetMetadataItem(ds.get(), "TIFFTAG_IMAGEDESCRIPTION", description.c_str(), nullptr);
    if (raster.layout == Raster::Layout::kEquirectangular && raster.radiusMetres > 0) {
      GDALSetMetadataItem(ds.get(), "AREA_OR_POINT", "Area", nullptr);
      double gt[6] = {-180.0, 360.0 / raster.width, 0.0, 90.0, 0.0, -180.0 / raster.height};
      GDALSetGeoTransform(ds.get(), gt);
      OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
      // A sphere of the planet's radius: inverse flattening 0.
      OSRSetGeogCS(srs, "PlanetSculpt planet", "PlanetSculpt sphere", "PlanetSculpt sphere",
                   raster.radiusMetres, 0.0, "Reference meridian", 0.0, SRS_UA_DEGREE,
                   std::stod(SRS_UA_DEGREE_CONV));
      GDALSetSpatialRef(ds.get(), srs);
      OSRDestroySpatialReference(srs);
    } else if (raster.layout == Raster::Layout::kFlat && raster.pixelWidthM > 0 &&
               raster.pixelHeightM > 0) {
      // Metres, no CRS; pixel-is-point with centres at (x dx, (height - 1 - y) dy).
      GDALSetMetadataItem(ds.get(), "AREA_OR_POINT", "Point", nullptr);
      double gt[6] = {-0.5 * raster.pixelWidthM,
                      raster.pixelWidthM,
                      0.0,
                      (raster.height - 0.5) * raster.pixelHeightM,
                      0.0,
                      -raster.pixelHeightM};
      GDALSetGeoTransform(ds.get(), gt);
    }
    GDALRasterBandH band = GDALGetRasterBand(ds.get(), 1);
    if (GDALRasterIO(band, GF_Write, 0, 0, raster.width, raster.height,
                     const_cast<float*>(raster.metres.data()), raster.width, raster.height,
                     GDT_Float32, 0, 0) != CE_None)
      throw std::runtime_error("cannot write " + path.string() + gdalMessage());
    GDALFlushCache(ds.get());
    ds.reset();  // closing writes the directory
    if (CPLGetLastErrorType() >= CE_Failure)
      throw std::runtime_error("cannot write " + path.string() + gdalMessage());
  });
}

}  // namespace ps::io
