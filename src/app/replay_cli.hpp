#pragma once
// The command-line options that `replay` and `demo` share: the markers, the tracker, the tool.
#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/replay_job.hpp"

namespace ps::app {

struct ReplayCli {
  ReplayJob job;
  std::string family = "tag36h11", mode = "raise", tool = "brush", material = "sand";
  long long grid = 2049;
  std::vector<double> tip = {0.0, -0.08, 0.0};
  double brushRadiusKm = 250, strengthM = 600, displaceRadiusKm = 400, pressM = 8000;
  bool noFilter = false, noSettle = false;
  std::string sun;  // "AZ,EL" in degrees; empty: the default sun (45, 35.26)
  bool noShadow = false, noAtmosphere = false, noHandMask = false;
  // The planet's markers: "single" (one marker, --planet-id/--planet-marker-size), "board" (the
  // committed markers/planet-board.json) or a layout file; the tool's: "flat" (one marker on a
  // stick, --tool-id/--tool-marker-size/--tip), "cube" (markers/tool-cube.json) or a file.
  // The board and the cube by default: a hand over the board or the cube turned edge-on does
  // not lose them. A recording made with the single markers replays with `--board single
  // --tool-layout flat` (or by itself, when its session sidecar says so).
  std::string board = "board", toolLayout = "cube";
  std::string chart = core::toString(kDefaultChart);  // the default planet's chart
  // Its dimensions (as `import` takes them): unset, the chart's defaults (app/default_planet.hpp).
  std::optional<double> radius, minorRadius, length;

  // Adds the shared options to `sub` (they write into this object, which must outlive it).
  void addOptions(CLI::App* sub);
  // Copies the parsed options into job.options and validates them (core::InputError).
  void apply();

 private:
  CLI::App* sub_ = nullptr;
};

}  // namespace ps::app
