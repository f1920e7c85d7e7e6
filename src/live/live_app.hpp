#pragma once
// The live app: a GLFW window (OpenGL 3.3 core) around the same pipeline as a replay
// (replay::FrameStepper: markers -> planet and tool -> strokes through the edit pipeline) and
// the same renderer as the headless path (render::PlanetRenderer): the AR view fills the window,
// the overview is an inset, a Dear ImGui panel changes the tool and the view (live/panel.hpp).
// The planet is saved atomically to OUT/planet.planet at the start, every `autosaveSeconds`,
// on Ctrl+S and when the window closes (Esc, Ctrl-C (SIGINT), the frame limit); between saves
// every finished stroke, undo and redo goes to OUT/planet.journal (session/session_store.hpp),
// and a journal left by a crashed session is offered for recovery at the start. A lost camera
// or an ended video shows a message and keeps the planet. docs/LIVE.md.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "live/frame_input.hpp"
#include "live/panel.hpp"
#include "replay/replay.hpp"
#include "terrain/terrain.hpp"
#include "tracking/calibration.hpp"

namespace ps::live {

// What to do with a journal of strokes a crashed session left in OUT (docs/LIVE.md).
enum class JournalChoice {
  kAsk,      // a modal in the window (Recover / Discard); closed undecided: left untouched
  kRecover,  // --recover: apply it to OUT/planet.planet and go on from there
  kDiscard,  // --discard-journal: move it aside (OUT/planet.journal.discarded)
};

struct LiveSettings {
  replay::ReplayOptions options;  // tool and brush at start; undo is switched on
  std::filesystem::path out = "out/live";
  int frames = 0;         // stop after this many window frames (0: until closed)
  int overviewEvery = 4;  // the overview inset is rendered every Nth frame
  double distMaxPx = 4.0;
  // The panel's toggles at start (`live --no-shadow`, `--no-atmosphere`, `--no-hand-mask`).
  bool boardShadow = true, atmosphere = true, handMask = true;
  std::size_t triangleBudget = 70000;
  // With `frames`: the window's last frame (AR view, inset, panel) as a PNG here.
  std::filesystem::path screenshot;
  double autosaveSeconds = 60;  // <= 0: no autosave (the journal still keeps every stroke)
  JournalChoice journal = JournalChoice::kAsk;
  // Record the frames the app processes to this video (FFV1 .mkv) from the start ("": only
  // when the panel's record toggle says so, to OUT/recording-NNN.mkv).
  std::filesystem::path record;
  // Panel actions and settings at given window frames (`--at FRAME:ACTION`, live/panel.hpp).
  std::vector<ScriptedAction> script;
  // Where the planet came from, for a recording's sidecar (replay/session_timeline.hpp): the
  // --planet file ("" : the default planet of `seed`) and the calibration file.
  struct Start {
    std::string planetFile;
    std::uint64_t seed = 1;
    std::string calibrationFile;
  } start;
};

struct LiveResult {
  int frames = 0;  // window frames drawn
  int strokes = 0;
  std::filesystem::path saved;  // where the planet went ("": not saved, see `journalKept`)
  int autosaves = 0;
  // The window closed while the recovery question was open: OUT/planet.planet and
  // OUT/planet.journal were left as they were (and nothing was sculpted).
  bool journalKept = false;
  std::vector<std::filesystem::path> recordings;  // videos written, with their frame counts
  std::vector<int> recordedFrames;
};

// Runs until the window closes, SIGINT or settings.frames. `planet` is the planet to start
// from; a recovered planet replaces it. Throws std::runtime_error when no window or OpenGL 3.3
// context can be made (no display), core::InputError for bad settings.
LiveResult runLive(FrameInput& input, const tracking::CameraCalibration& calibration,
                   std::unique_ptr<terrain::Terrain>& planet, const LiveSettings& settings);

}  // namespace ps::live
