// `planetsculpt bench roundtrip`: a global equirectangular DEM through a planet and back (issue
// 43: `import` onto each sphere chart at the default grid, `export` to equirectangular at the
// DEM's own size, cubic both ways), compared pixel by pixel with the file. Lat-long and the
// octahedral chart in one run, on the shared Mars MOLA grid (1440x720; ../shared/data/dem).
//
// JSON lines, one per chart: rms_m, p99_m, max_m over every pixel; rms_per_area_m (each pixel
// weighted by cos latitude); the rows within 5 degrees of each pole (polar_*, both caps together,
// and north_* / south_* apart) against the rows within 5 degrees of the equator (equator_*);
// polar_floor_rms_m and equator_floor_rms_m: what the DEM holds along those rows' parallels that
// is narrower than the grid's spacing there (each pixel less the mean of the pixels within half
// a spacing along its row: a yardstick for what a grid of that spacing cannot hold, not a
// strict bound);
// band_rms_m: the rms of each 10-degree band of latitude, north to south; rms_vs_latlong and
// p99_vs_latlong against lat-long's in the same run; import_ms and export_ms (one run each).
// --quick: 2049^2 instead of the default grid; --grid SIDE: that grid for both.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <vector>

#include "app/build_paths.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "io/height_image.hpp"
#include "io/heightmap_export.hpp"
#include "io/heightmap_import.hpp"
#include "terrain/terrain.hpp"

namespace ps::bench {

namespace {

namespace fs = std::filesystem;

// Errors of the pixels in one group of rows.
struct ErrorSet {
  std::vector<double> abs;
  double ss = 0;
  void add(double e) {
    abs.push_back(std::abs(e));
    ss += e * e;
  }
  double rms() const { return abs.empty() ? 0 : std::sqrt(ss / double(abs.size())); }
  double p99() const { return percentile(abs, 0.99); }
};

// What the DEM holds along its parallels that is narrower than the grid's spacing there: the
// rms of each pixel less the mean of the pixels within half a spacing of it along its row, over
// the rows with |latitude| >= `fromDeg` (and <= `toDeg`): about what a grid of that spacing
// cannot hold in those rows (a box filter's estimate, not a strict bound). `spacingRad(latRad)`:
// the grid's spacing along the parallel as an angle of arc.
template <class Spacing>
double detailBelowSpacing(const io::HeightImage& img, double fromDeg, double toDeg,
                          Spacing spacingRad) {
  const int w = img.width, h = img.height;
  double ss = 0;
  long long n = 0;
  for (int y = 0; y < h; ++y) {
    const double latDeg = 90.0 - 180.0 * (y + 0.5) / h;
    if (std::abs(latDeg) < fromDeg || std::abs(latDeg) > toDeg) continue;
    const double lat = latDeg * std::numbers::pi / 180;
    const double pixelArc = 2 * std::numbers::pi / w * std::cos(lat);
    const int half = std::min(w / 2, int(std::lround(0.5 * spacingRad(lat) / pixelArc)));
    const float* row = img.values.data() + std::size_t(y) * std::size_t(w);
    for (int x = 0; x < w; ++x) {
      double sum = 0;
      for (int k = -half; k <= half; ++k) sum += row[((x + k) % w + w) % w];
      const double e = row[x] - sum / (2 * half + 1);
      ss += e * e;
      ++n;
    }
  }
  return std::sqrt(ss / double(n));
}

nlohmann::json measureChart(const io::HeightImage& original, const fs::path& file,
                            io::ChartKind chart, long long gridSide) {
  io::ImportOptions o;
  o.chart = chart;
  o.radius = 3389500.0;  // Mars' mean radius (the DEM's README)
  o.offset = -32768.0;
  o.westLongitudeDeg = -180.0;  // so that the export's column 0 is the file's
  o.gridSide = gridSide;
  std::optional<io::ImportResult> r;
  const double importMs = timeMs([&] { r = io::importHeightmap(file, o); });
  const terrain::Terrain t(r->planet.chart, r->planet.heights);
  const int w = original.width, h = original.height;
  io::Raster back;
  const double exportMs = timeMs([&] { back = io::resampleEquirectangular(t, w, h); });

  ErrorSet all, north, south, equator;
  std::vector<ErrorSet> bands(18);
  double ssArea = 0, area = 0;
  for (int y = 0; y < h; ++y) {
    const double latDeg = 90.0 - 180.0 * (y + 0.5) / h;
    const double weight = std::cos(latDeg * std::numbers::pi / 180);
    ErrorSet& band = bands[std::size_t(std::clamp(int((90.0 - latDeg) / 10), 0, 17))];
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
      const double e = double(back.metres[i]) - (double(original.values[i]) - 32768.0);
      all.add(e);
      band.add(e);
      ssArea += weight * e * e;
      area += weight;
      if (latDeg >= 85) north.add(e);
      if (latDeg <= -85) south.add(e);
      if (std::abs(latDeg) <= 5) equator.add(e);
    }
  }
  ErrorSet polar = north;
  for (double e : south.abs) polar.add(e);
  const double m = t.chart().grid().m();
  const bool latlong = chart == io::ChartKind::kLatLong;
  // Lat-long: a column every 2 pi / m radians of longitude; the octahedral grid: its mean
  // spacing, sqrt(4 pi) / m (m^2 cells of one area).
  auto spacing = [&](double lat) {
    return latlong ? 2 * std::numbers::pi / m * std::cos(lat) : std::sqrt(4 * std::numbers::pi) / m;
  };
  std::vector<double> bandRms;
  for (const auto& b : bands) bandRms.push_back(std::round(b.rms() * 100) / 100);
  return {{"bench", "roundtrip"},
          {"dem", file.filename().string()},
          {"size", std::to_string(w) + "x" + std::to_string(h)},
          {"chart", t.chart().name()},
          {"grid", t.chart().grid().side()},
          {"interpolation", "cubic"},
          {"rms_m", all.rms()},
          {"p99_m", all.p99()},
          {"max_m", *std::max_element(all.abs.begin(), all.abs.end())},
          {"rms_per_area_m", std::sqrt(ssArea / area)},
          {"polar_rms_m", polar.rms()},
          {"polar_p99_m", polar.p99()},
          {"north_rms_m", north.rms()},
          {"north_p99_m", north.p99()},
          {"south_rms_m", south.rms()},
          {"south_p99_m", south.p99()},
          {"equator_rms_m", equator.rms()},
          {"equator_p99_m", equator.p99()},
          {"polar_floor_rms_m", detailBelowSpacing(original, 85, 90, spacing)},
          {"equator_floor_rms_m", detailBelowSpacing(original, 0, 5, spacing)},
          {"band_rms_m", bandRms},
          {"import_ms", importMs},
          {"export_ms", exportMs}};
}

void benchRoundTrip(const BenchOptions& options, long long gridSide, std::ostream& out) {
  const fs::path file = app::sharedDir() / "data/dem/mars_mola_1440x720_u16.png";
  if (!fs::exists(file)) {
    std::cerr << "bench roundtrip: " << file.string() << " is absent; nothing measured\n";
    return;
  }
  const io::HeightImage original = io::readHeightImage(file);
  long long grid = options.quick ? 2049 : 0;  // 0: each chart's default grid
  if (gridSide > 0) grid = gridSide;
  nlohmann::json latlong;
  for (const io::ChartKind chart : {io::ChartKind::kLatLong, io::ChartKind::kOctahedral}) {
    std::cerr << "bench roundtrip: " << core::toString(chart) << "\n";
    nlohmann::json row = measureChart(original, file, chart, grid);
    if (chart == io::ChartKind::kLatLong) latlong = row;
    row["rms_vs_latlong"] = row["rms_m"].get<double>() / latlong["rms_m"].get<double>();
    row["p99_vs_latlong"] = row["p99_m"].get<double>() / latlong["p99_m"].get<double>();
    out << row.dump() << std::endl;
  }
}

const BenchRegistration kRoundTrip(
    "roundtrip", "a global DEM through lat-long and the octahedral chart and back, the poles apart",
    [](CLI::App& command) -> BenchFunction {
      auto side = std::make_shared<long long>(0);
      command
          .add_option("--grid", *side, "The grid's side for both charts (default: each chart's)")
          ->check(CLI::Validator(notAGridSide, "2^n+1"));
      return [side](const BenchOptions& o, std::ostream& out) { benchRoundTrip(o, *side, out); };
    });

}  // namespace

}  // namespace ps::bench
