#pragma once
// A replay from files to files, shared by `planetsculpt replay` and `planetsculpt demo`: loads
// the video, calibration and planet (or makes the default one), replays (replay/replay.hpp), and
// writes the sculpted planet, its heightmap, the logs, a summary and (optionally) pictures.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/default_planet.hpp"
#include "core/chart_factory.hpp"
#include "replay/replay.hpp"

namespace ps::app {

struct ReplayJob {
  std::filesystem::path video, calibration, out = "out/replay";
  std::filesystem::path planetFile;  // empty: the default planet
  int gridLevel = 11;                // default planet: 2049^2
  std::uint64_t seed = 1;
  core::ChartShape chart = kDefaultChart;  // default planet's chart (`--chart`)
  PlanetDims dims;  // its dimensions (`--radius`, `--minor-radius`, `--length`)
  replay::ReplayOptions options;
  // Pictures: relief.png (after), relief_before.png, closeup.png (before | after around what
  // changed), view.png and view_wireframe.png (a tessellated view of the sculpted region).
  // With pictures, also the AR showcase (ar_view.png, overview.png: the middle frame of the
  // longest touching run) when headless OpenGL is available.
  bool pictures = false;
  // AR frames: DIR/ar/frame_NNNNN.png and overview_NNNNN.png every renderEvery frames (needs
  // headless OpenGL; an error when there is none).
  bool render = false;
  int renderEvery = 1;
  // The AR frames' light (render/atmosphere_passes.hpp): the sun in the board's frame (x, y on
  // the board, z up from it; `--sun AZ,EL`), the planet's shadow on the board and the atmosphere
  // rim (`--no-shadow`, `--no-atmosphere`).
  Eigen::Vector3d sun = Eigen::Vector3d(1, 1, 1).normalized();
  bool boardShadow = true, atmosphere = true;
  // The camera image over the planet where a hand is in front of it (tracking/hand_mask.hpp;
  // `--no-hand-mask`).
  bool handMask = true;
  // The haptic force path run offline beside the replay (forces only: the tool's edits stay the
  // replay's): OUT/forces.csv, one row per 1 kHz tick (haptics/force_log.hpp).
  bool forces = true;
  double distMaxPx = 4.0;
  std::size_t triangleBudget = 70000;
  // A live session's settings timeline (replay/session_timeline.hpp): `session`, else
  // VIDEO.session.jsonl when it exists; none with noSession. The sidecar's settings win over
  // `options` and the default planet's grid and seed; `givenOptions` (those typed on the
  // command line) are named in a warning then.
  std::filesystem::path session;
  bool noSession = false;
  std::vector<std::string> givenOptions;
};

// Runs the job; returns the summary it also writes to out/summary.json. Throws
// core::InputError (bad settings or inputs, before anything is written) and std::runtime_error
// (files that cannot be written).
nlohmann::json runReplayJob(const ReplayJob& job);

}  // namespace ps::app
