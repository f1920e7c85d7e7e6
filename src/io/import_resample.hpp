#pragma once
// A heightmap in metres onto a chart's grid, for `planetsculpt import`: an equirectangular image
// onto a sphere chart (lat-long, octahedral), a flat image onto a flat chart, an image of a
// torus's or cylinder's own (u, v) grid onto that chart.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/grid.hpp"
#include "io/heightmap_import.hpp"

namespace ps::io::import_detail {

// The largest equirectangular image a sphere chart's grid of side m + 1 samples as it is (a finer
// one is area-averaged down to it first).
std::pair<int, int> averagedSize(ChartKind chart, int m);

// Tells the user which radius the planet takes and where it came from.
void noteRadius(double radius, const ImportOptions& o, const HeightImage& img, ImportResult& res);

// The equirectangular image onto a lat-long grid: area-averaged first where the image is finer,
// then interpolated (o.interpolation); pole rows one point each.
void resampleLatLong(const HeightImage& img, const ImportOptions& o, double radius,
                     const core::GridSize& g, const std::string& name, std::vector<float>& heights,
                     ImportResult& res, nlohmann::json& source);
// The equirectangular image onto any other sphere chart (the octahedral one): each grid vertex
// samples the image at its own direction's latitude and longitude.
void resampleSphere(const HeightImage& img, const ImportOptions& o, double radius,
                    const core::GridSize& g, const std::string& name, std::vector<float>& heights,
                    ImportResult& res, nlohmann::json& source);
// A sphere chart takes a global equirectangular image (row 0 at 90 N, 360 x 180 degrees): any
// other georeferencing is refused naming the file.
void checkCoversTheGlobe(const HeightImage& img, core::ChartShape chart, const std::string& name);

struct PixelSpacing {
  double x = 1.0, y = 1.0;
  std::string from;
};
// Metres between a flat image's pixel centres: the user's, the file's own metadata or its
// GeoTIFF pixel scale.
PixelSpacing flatSpacing(const HeightImage& img, const ImportOptions& o, const std::string& name);
// A flat image onto a flat chart's grid (o.interpolation).
void resampleFlat(const HeightImage& img, const ImportOptions& o, const core::GridSize& g,
                  const std::string& name, std::vector<float>& heights, ImportResult& res,
                  nlohmann::json& source);
// An image of a torus's or a cylinder's (u, v) grid (io::resampleTube's layout) onto that chart.
void resampleTubeImage(const HeightImage& img, const ImportOptions& o, double radius,
                       const core::GridSize& g, const std::string& name,
                       std::vector<float>& heights, ImportResult& res, nlohmann::json& source);

}  // namespace ps::io::import_detail
