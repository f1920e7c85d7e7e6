// `planetsculpt import FILE --out PLANET`: a user's heightmap (8/16-bit grey PNG, TIFF/GeoTIFF,
// raw float32 + sidecar) becomes a planet file. No-data is filled or refused, and the user is told.
#include <cmath>
#include <iostream>
#include <memory>

#include "app/command_registry.hpp"
#include "app/default_planet.hpp"
#include "core/input_error.hpp"
#include "io/heightmap_import.hpp"
#include "io/planet_file.hpp"

namespace ps::app {

namespace {

struct ImportArgs {
  std::string input, output, chart = core::toString(kDefaultChart), noData = "fill", noDataValue,
                             encoding = "stored", store = "f32", rule = "hybrid-exact",
                             interpolation = "cubic";
  std::optional<double> radius, minorRadius, length, scale, offset, westLon, spacing;
  long long grid = 0;
};

int runImport(const ImportArgs& a) {
  io::ImportOptions o;
  o.chart = io::chartKindFromString(a.chart);
  o.radius = a.radius;
  o.minorRadius = a.minorRadius;
  o.length = a.length;
  o.scale = a.scale;
  o.offset = a.offset;
  o.gridSide = a.grid;
  o.noData = io::noDataPolicyFromString(a.noData);
  if (!a.noDataValue.empty()) o.noDataValue = io::noDataValueFromString(a.noDataValue);
  o.westLongitudeDeg = a.westLon;
  o.spacing = a.spacing;
  o.rule = terrain::errorRuleFromString(a.rule);
  o.interpolation = io::interpolationFromString(a.interpolation);
  // --encoding f32|u16 named the planet file's storage before web DEM tiles were read: those two
  // values still do, as --store does.
  std::string store = a.store;
  if (a.encoding == "f32" || a.encoding == "u16") {
    store = a.encoding;
  } else {
    o.encoding = io::pngHeightEncodingFromString(a.encoding);
  }
  io::ImportResult r = io::importHeightmap(a.input, o);
  for (const auto& note : r.notes) std::cerr << "import: " << a.input << ": " << note << "\n";
  io::PlanetSaveOptions save;
  save.encoding = io::heightEncodingFromString(store);
  save.metadata = r.planet.metadata;
  io::savePlanet(*r.planet.chart, r.planet.heights, r.planet.rule, a.output, save);
  const auto [lo, hi] = std::minmax_element(r.planet.heights.begin(), r.planet.heights.end());
  std::cout << "wrote " << a.output << ": " << r.planet.chart->name() << " planet, "
            << r.planet.chart->grid().label() << " grid, heights " << *lo << " .. " << *hi << " m";
  if (r.planet.chart->sphereRadius() > 0)
    std::cout << ", radius " << r.planet.chart->sphereRadius() << " m";
  if (r.noDataPixels > 0) std::cout << ", " << r.noDataPixels << " no-data pixels filled";
  std::cout << "\n";
  return 0;
}

const CommandRegistration kImport([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<ImportArgs>();
  sub = root.add_subcommand(
      "import", "Make a planet file from a heightmap (PNG, TIFF/GeoTIFF, raw float32 + sidecar)");
  sub->add_option("file", a->input,
                  "Heightmap: 8/16-bit grey PNG, TIFF (int or float), raw float32 with FILE.json")
      ->required();
  sub->add_option("--out", a->output, "Planet file to write (atomically)")->required();
  sub->add_option("--chart", a->chart,
                  "latlong or octahedral (a global equirectangular image onto a sphere of that "
                  "chart; docs/CHARTS.md), flat (a terrain tile), torus or cylinder (an image "
                  "of its (u, v) grid, as export writes it: docs/EXPORT.md)")
      ->capture_default_str();
  sub->add_option("--radius", a->radius,
                  "Planet radius in metres (a sphere; default: the file's, else " +
                      std::to_string(int(io::kDefaultImportRadius)) +
                      "; a torus's major radius or a cylinder's radius: required)");
  sub->add_option("--minor-radius", a->minorRadius,
                  "torus: the tube's radius in metres (below --radius)");
  sub->add_option("--length", a->length, "cylinder: its length in metres");
  sub->add_option("--scale", a->scale, "Height in metres = value * scale + offset");
  sub->add_option("--offset", a->offset, "Height in metres = value * scale + offset");
  sub->add_option("--grid", a->grid,
                  "Grid side 2^n+1 (default: the smallest that keeps the image's detail)");
  sub->add_option("--west-lon", a->westLon,
                  "latlong: longitude of the image's western edge in degrees (default -180)");
  sub->add_option("--spacing", a->spacing,
                  "flat: metres between pixels (default: from the file, else 1)");
  sub->add_option("--nodata", a->noData, "fill (harmonic interpolation) or refuse no-data pixels")
      ->capture_default_str();
  sub->add_option("--nodata-value", a->noDataValue, "Declare the no-data value (a number or nan)");
  sub->add_option("--encoding", a->encoding,
                  "PNG input: heights as stored (grey), or a web DEM tile's terrain-rgb (Mapbox) "
                  "or terrarium packing (f32 and u16 are taken as --store, as before)")
      ->capture_default_str();
  sub->add_option("--store", a->store,
                  "Planet file heights: f32 (exact) or u16 (quantised, half the size)")
      ->capture_default_str();
  sub->add_option("--interpolation", a->interpolation,
                  "Sampling the image at the grid's vertices: cubic (Catmull-Rom) or bilinear")
      ->capture_default_str();
  sub->add_option("--error-rule", a->rule, "Error bounds: hybrid-exact or wedgie")
      ->capture_default_str();
  return [a] { return runImport(*a); };
});

}  // namespace
}  // namespace ps::app
