#include "app/replay_cli.hpp"
#include "app/build_paths.hpp"

#include <filesystem>
#include <memory>

#include "core/grid.hpp"
#include "core/input_error.hpp"
#include "render/sun.hpp"
#include "sand/material.hpp"
#include "tracking/marker_layout.hpp"

namespace ps::app {

namespace {

// A layout option's value: a keyword for the committed file, or a path (relative paths that do
// not exist from here are looked for in the source tree, as the bundled files are).
std::shared_ptr<const tracking::MarkerLayout> layoutFrom(const std::string& value,
                                                         const std::string& keyword,
                                                         const std::filesystem::path& committed) {
  std::filesystem::path p = value == keyword ? committed : std::filesystem::path(value);
  if (!std::filesystem::exists(p) && p.is_relative() &&
      std::filesystem::exists(ps::app::sourceDir() / p))
    p = ps::app::sourceDir() / p;
  return std::make_shared<const tracking::MarkerLayout>(tracking::loadMarkerLayout(p));
}

}  // namespace

void ReplayCli::addOptions(CLI::App* sub) {
  sub_ = sub;
  auto& o = job.options;
  sub->add_option("--planet", job.planetFile, "Sculpt this planet file instead of the default");
  sub->add_option("--grid", grid, "Default planet's grid side (2^n+1)")->capture_default_str();
  sub->add_option("--chart", chart,
                  "Default planet's chart: latlong (paper 003), octahedral (no poles, cells of "
                  "equal area), octahedral-central, torus or cylinder (docs/CHARTS.md)")
      ->capture_default_str();
  sub->add_option("--radius", radius,
                  "Default planet's radius in metres: a sphere's (default 6372790), a torus's "
                  "major radius (default 4500000), a cylinder's (default 6000000)");
  sub->add_option("--minor-radius", minorRadius,
                  "Default torus's tube radius in metres, below --radius (default 1800000)");
  sub->add_option("--length", length, "Default cylinder's length in metres (default 4000000)");
  sub->add_option("--seed", job.seed, "Default planet's relief seed")->capture_default_str();
  sub->add_option("--family", family,
                  "Family of the single markers (--board single, --tool-layout flat); layout "
                  "files name their own, and every family they name is detected")
      ->capture_default_str();
  sub->add_option("--decimate", o.detector.decimate, "AprilTag search decimation")
      ->capture_default_str();
  sub->add_option("--planet-id", o.scene.planet.id, "Planet marker id")->capture_default_str();
  sub->add_option("--planet-marker-size", o.scene.planet.size, "Planet marker edge (m)")
      ->capture_default_str();
  sub->add_option("--planet-radius", o.scene.planetRadius, "Displayed planet radius (m)")
      ->capture_default_str();
  sub->add_option("--board", board,
                  "Planet markers: single (one marker: --planet-id, --planet-marker-size), board "
                  "(markers/planet-board.json) or a board layout file")
      ->capture_default_str();
  sub->add_option("--tool-layout", toolLayout,
                  "Tool markers: flat (one marker on a stick: --tool-id, --tool-marker-size, "
                  "--tip), cube (markers/tool-cube.json) or a tool layout file")
      ->capture_default_str();
  sub->add_option("--tool-id", o.scene.tool.id, "Tool marker id")->capture_default_str();
  sub->add_option("--tool-marker-size", o.scene.tool.size, "Tool marker edge (m)")
      ->capture_default_str();
  sub->add_option("--tip", tip, "Tool tip in the tool marker's frame, X,Y,Z (m)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--touch", o.scene.touchDistance, "Touching within this height (m)")
      ->capture_default_str();
  sub->add_option("--tool", tool,
                  "What touching does: brush (Gaussian), displace (sand on the grid) or tin-sand "
                  "(sand on a TIN, paper 000: the displacement's radius and --press-m)")
      ->capture_default_str();
  sub->add_option("--brush-radius-km", brushRadiusKm, "Brush radius r_d on the planet (km)")
      ->capture_default_str();
  sub->add_option("--strength-m", strengthM, "Height change per stamp at the centre (m)")
      ->capture_default_str();
  sub->add_option("--mode", mode, "Brush mode: raise, lower or set")->capture_default_str();
  sub->add_option("--displace-radius-km", displaceRadiusKm, "Displacement sphere radius (km)")
      ->capture_default_str();
  sub->add_option("--press-m", pressM, "How deep the displacement sphere presses in (m)")
      ->capture_default_str();
  sub->add_option("--material", material,
                  "What the sand tools press and settle: sand (talus 30 deg), mud (72 deg, "
                  "cohesive) or pebbles (60 deg) (docs/SAND.md, \"Materials\")")
      ->capture_default_str();
  sub->add_flag("--no-settle", noSettle, "Displace: do not let the sand settle");
  sub->add_option("--max-frames", o.maxFrames, "Stop after this many frames (0: all)");
  sub->add_flag("--no-filter", noFilter, "Use raw poses (no One Euro filters)");
  sub->add_option("--sun", sun,
                  "AR frames: the sun's azimuth (from the board's +x toward +y) and elevation "
                  "above the board, AZ,EL in degrees (default 45,35.26)");
  sub->add_flag("--no-shadow", noShadow, "AR frames: no shadow of the planet on the board");
  sub->add_flag("--no-atmosphere", noAtmosphere, "AR frames: no atmosphere rim");
  sub->add_flag("--no-hand-mask", noHandMask,
                "AR frames: draw the planet over a hand in front of it (no hand mask)");
}

void ReplayCli::apply() {
  auto& o = job.options;
  o.detector.family = family;
  if (tip.size() != 3) throw core::InputError("--tip needs three numbers X,Y,Z (metres)");
  o.scene.tipOffset = {tip[0], tip[1], tip[2]};
  o.tool = replay::replayToolFromString(tool);
  o.brush.radius = brushRadiusKm * 1e3;
  o.brush.strength = strengthM;
  o.brush.mode = edit::brushModeFromString(mode);
  o.displace.radius = displaceRadiusKm * 1e3;
  o.pressDepth = pressM;
  o.displace.material = sand::Material::preset(material);
  o.settle = !noSettle;
  if (noFilter) o.scene.planet.filter = o.scene.tool.filter = o.scene.filterTip = false;
  o.scene.useBoard(board == "single" ? nullptr
                                     : layoutFrom(board, "board", "markers/planet-board.json"));
  o.scene.useToolLayout(
      toolLayout == "flat" ? nullptr : layoutFrom(toolLayout, "cube", "markers/tool-cube.json"));
  job.gridLevel = core::GridSize::fromSide(grid).n();
  job.chart = core::chartShapeFromString(chart);
  if (!job.planetFile.empty() && sub_ && sub_->get_option("--chart")->count() > 0)
    throw core::InputError("--chart makes a new default planet; the planet file " +
                           job.planetFile.string() + " has its own chart");
  job.dims = {radius, minorRadius, length};
  if (!job.planetFile.empty() && (radius || minorRadius || length))
    throw core::InputError(std::string(radius        ? "--radius"
                                       : minorRadius ? "--minor-radius"
                                                     : "--length") +
                           " sizes a new default planet; the planet file " +
                           job.planetFile.string() + " has its own dimensions");
  if (job.planetFile.empty()) (void)resolveDims(job.chart, job.dims);  // names a bad option now
  if (!sun.empty()) job.sun = render::sunDirection(render::parseSunAngles(sun, "--sun"));
  job.boardShadow = !noShadow;
  job.atmosphere = !noAtmosphere;
  job.handMask = !noHandMask;
  o.validate();
  // What a session sidecar replaces (app/replay_job.hpp), when typed.
  for (const char* name : {"--grid",
                           "--chart",
                           "--radius",
                           "--minor-radius",
                           "--length",
                           "--seed",
                           "--family",
                           "--decimate",
                           "--planet-id",
                           "--planet-marker-size",
                           "--planet-radius",
                           "--tool-id",
                           "--tool-marker-size",
                           "--tip",
                           "--touch",
                           "--tool",
                           "--brush-radius-km",
                           "--strength-m",
                           "--mode",
                           "--displace-radius-km",
                           "--press-m",
                           "--material",
                           "--no-settle",
                           "--no-filter"})
    if (sub_ && sub_->get_option(name)->count() > 0) job.givenOptions.push_back(name);
}

}  // namespace ps::app
