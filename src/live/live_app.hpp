#pragma once
// The live app: a GLFW window (OpenGL 3.3 core) around the same pipeline as a replay
// (replay::FrameStepper: markers -> planet and tool -> strokes through the edit pipeline) and
// the same renderer as the headless path (render::PlanetRenderer): the AR view fills the window,
// the overview is an inset, a Dear ImGui panel changes the tool and the view (live/panel.hpp).
// Closing the window, Esc, Ctrl-C (SIGINT) or the frame limit saves the planet atomically to
// OUT/planet.planet. A lost camera or an ended video shows a message and keeps the planet.
#include <filesystem>

#include "live/frame_input.hpp"
#include "replay/replay.hpp"
#include "terrain/terrain.hpp"
#include "tracking/calibration.hpp"

namespace ps::live {

struct LiveSettings {
  replay::ReplayOptions options;  // tool and brush at start; undo is switched on
  std::filesystem::path out = "out/live";
  int frames = 0;         // stop after this many window frames (0: until closed)
  int overviewEvery = 4;  // the overview inset is rendered every Nth frame
  double distMaxPx = 4.0;
  std::size_t triangleBudget = 70000;
  // With `frames`: the window's last frame (AR view, inset, panel) as a PNG here.
  std::filesystem::path screenshot;
};

struct LiveResult {
  int frames = 0;  // window frames drawn
  int strokes = 0;
  std::filesystem::path saved;  // where the planet went
};

// Runs until the window closes, SIGINT or settings.frames. Throws std::runtime_error when no
// window or OpenGL 3.3 context can be made (no display), core::InputError for bad settings.
LiveResult runLive(FrameInput& input, const tracking::CameraCalibration& calibration,
                   terrain::Terrain& planet, const LiveSettings& settings);

}  // namespace ps::live
