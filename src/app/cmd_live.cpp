// `planetsculpt live --camera N | --video FILE --calib FILE [--planet FILE] [--out DIR]
// [--frames N] [--autosave-s S] [--recover | --discard-journal] [--record FILE]`: the interactive
// app (live/live_app.hpp): a window with the AR view, the overview inset and a panel; the planet
// follows the planet marker and the tool marker sculpts while it touches. Built only when GLFW 3.3
// and Dear ImGui were found (CMakeLists.txt).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "app/command_registry.hpp"
#include "app/default_planet.hpp"
#include "app/replay_cli.hpp"
#include "core/input_error.hpp"
#include "io/planet_file.hpp"
#include "live/live_app.hpp"
#include "live/panel.hpp"
#include "session/frame_recorder.hpp"

namespace ps::app {
namespace {

struct LiveArgs {
  ReplayCli cli;  // the replay's marker, tracker and tool options (one set for both commands)
  int camera = -1;
  std::string video;
  live::LiveSettings settings;
  bool recover = false, discard = false;
  std::vector<std::string> script;  // --at FRAME:ACTION
};

const CommandRegistration kLive([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<LiveArgs>();
  a->cli.job.out = "out/live";
  sub = root.add_subcommand("live",
                            "Sculpt live: a webcam (or video) in a window with the AR view, "
                            "the overview and a panel");
  sub->footer(std::string("Keys:\n") + live::shortcutHelp());
  auto* camera = sub->add_option("--camera", a->camera, "Camera index (0, 1, ...)");
  auto* video = sub->add_option("--video", a->video, "A video file instead of a camera");
  camera->excludes(video);
  sub->add_option("--calib", a->cli.job.calibration, "Camera calibration (OpenCV YAML)")
      ->required();
  sub->add_option("--out", a->cli.job.out, "Where the planet is saved (OUT/planet.planet)")
      ->capture_default_str();
  sub->add_option("--frames", a->settings.frames, "Quit (and save) after N frames (0: never)")
      ->capture_default_str();
  sub->add_option("--dist-max", a->settings.distMaxPx, "Screen-space error bound (px)")
      ->capture_default_str();
  sub->add_option("--budget", a->settings.triangleBudget, "Triangle budget")->capture_default_str();
  sub->add_option("--overview-every", a->settings.overviewEvery,
                  "Render the overview inset every Nth frame")
      ->capture_default_str();
  sub->add_option("--screenshot", a->settings.screenshot,
                  "With --frames: the window's last frame as a PNG");
  sub->add_option("--autosave-s", a->settings.autosaveSeconds,
                  "Save the planet every S seconds between strokes (0: only on Ctrl+S and at the "
                  "end); the stroke journal OUT/planet.journal keeps every stroke in between")
      ->capture_default_str();
  auto* recover = sub->add_flag("--recover", a->recover,
                                "Apply the stroke journal a crashed session left in OUT to "
                                "OUT/planet.planet and go on from there");
  auto* discard = sub->add_flag("--discard-journal", a->discard,
                                "Set such a journal aside (OUT/planet.journal.discarded)");
  recover->excludes(discard);
  sub->add_option("--record", a->settings.record,
                  "Record the frames the app processes to FILE (FFV1 .mkv: `planetsculpt replay "
                  "FILE` replays the session; the settings changed while recording go to "
                  "FILE.session.jsonl beside it); a folder gets the next recording-NNN.mkv");
  sub->add_option("--at", a->script,
                  "FRAME:ACTION, repeatable: a panel action at a window frame as if its key were "
                  "pressed (export, record, save, undo, redo, quit), or FRAME:SETTING=VALUE as "
                  "if the panel were set "
                  "so (tool=brush|displace|tin-sand, mode=raise|lower, material=sand|mud|pebbles, "
                  "radius_km, strength_m, sigma, "
                  "displace_radius_km, press_m, size_cm, spin_deg, tilt_deg): scripted sessions "
                  "for tests and demos");
  a->cli.addOptions(sub);
  return [a] {
    for (const auto& s : a->script) a->settings.script.push_back(live::parseScriptedAction(s));
    if ((a->camera < 0) == a->video.empty())
      throw core::InputError("live needs --camera N or --video FILE");
    a->cli.apply();
    const ReplayJob& job = a->cli.job;
    // Inputs first: a bad camera, video or calibration costs nothing.
    live::FrameInput input =
        a->camera >= 0 ? live::FrameInput::camera(a->camera) : live::FrameInput::video(a->video);
    const auto calib = tracking::loadCalibration(job.calibration);
    calib.forImageSize(input.size());  // refuses another aspect ratio, naming the file
    std::unique_ptr<terrain::Terrain> planet =
        job.planetFile.empty() ? makeDefaultPlanet(job.gridLevel, job.seed, job.chart, job.dims)
                               : io::loadPlanet(job.planetFile);
    a->settings.options = job.options;
    a->settings.start = {job.planetFile.string(), job.seed, job.calibration.string()};
    a->settings.out = job.out;
    a->settings.boardShadow = job.boardShadow;
    a->settings.atmosphere = job.atmosphere;
    a->settings.handMask = job.handMask;
    a->settings.journal = a->recover   ? live::JournalChoice::kRecover
                          : a->discard ? live::JournalChoice::kDiscard
                                       : live::JournalChoice::kAsk;
    if (a->settings.autosaveSeconds < 0 || !std::isfinite(a->settings.autosaveSeconds))
      throw core::InputError("--autosave-s must be >= 0 (0: no autosave)");
    // `--record DIR` (an existing folder, or a path ending in a separator): the next free
    // DIR/recording-NNN.mkv, as the panel's record toggle names them in OUT.
    if (!a->settings.record.empty()) {
      const std::filesystem::path rec = a->settings.record;
      if (std::filesystem::is_directory(rec) || !rec.has_filename()) {
        std::filesystem::create_directories(rec);
        a->settings.record = session::nextRecordingPath(rec);
      }
    }
    const auto r = live::runLive(input, calib, planet, a->settings);
    for (std::size_t i = 0; i < r.recordings.size(); ++i)
      std::cout << "live: recorded " << r.recordedFrames[i] << " frames to "
                << r.recordings[i].string() << "\n";
    if (r.journalKept) {
      std::cout << "live: " << r.frames << " frames; nothing sculpted or saved: "
                << (std::filesystem::path(job.out) / "planet.journal").string()
                << " was left untouched (run with --recover or --discard-journal)\n";
      return 0;
    }
    std::cout << "live: " << r.frames << " frames, " << r.strokes << " strokes; saved "
              << r.saved.string() << " (" << r.autosaves << " autosaves)\n";
    return 0;
  };
});

}  // namespace
}  // namespace ps::app
