#pragma once
// The live app's sculpting loop: each window frame reads the camera, steps the tracker and the
// edit pipeline (replay::FrameStepper, as a replay does), keeps the files (autosave, stroke
// journal, recording with its sidecar, exports), feeds the haptic force path, draws the AR view
// and the panel, and applies what the user asked for. docs/LIVE.md.
#include <Eigen/Core>

#include "live/live_shell.hpp"
#include "replay/replay.hpp"
#include "session/session_store.hpp"
#include "terrain/terrain.hpp"
#include "tracking/calibration.hpp"

namespace ps::live {

// Runs until the window closes, Ctrl-C or the frame limit, then saves the planet (and saves it
// before any error goes on). `recovered`: the planet came from a crashed session's journal, so
// a recording starts from a copy of it.
void runSculptLoop(Shell& shell, const tracking::CameraCalibration& calib, const Eigen::Matrix3d& K,
                   const replay::ReplayOptions& options, terrain::Terrain& planet, bool recovered,
                   const session::SessionFiles& files);

}  // namespace ps::live
