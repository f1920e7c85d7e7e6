// `planetsculpt live --camera N | --video FILE --calib FILE [--planet FILE] [--out DIR]
// [--frames N]`: the interactive app (live/live_app.hpp): a window with the AR view, the
// overview inset and a panel; the planet follows the planet marker and the tool marker sculpts
// while it touches. Built only when GLFW 3.3 and Dear ImGui were found (CMakeLists.txt).
#include <iostream>
#include <memory>

#include "app/command_registry.hpp"
#include "app/default_planet.hpp"
#include "app/replay_cli.hpp"
#include "core/input_error.hpp"
#include "io/planet_file.hpp"
#include "live/live_app.hpp"
#include "live/panel.hpp"

namespace ps::app {
namespace {

struct LiveArgs {
  ReplayCli cli;  // the replay's marker, tracker and tool options (one set for both commands)
  int camera = -1;
  std::string video;
  live::LiveSettings settings;
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
  a->cli.addOptions(sub);
  return [a] {
    if ((a->camera < 0) == a->video.empty())
      throw core::InputError("live needs --camera N or --video FILE");
    a->cli.apply();
    const ReplayJob& job = a->cli.job;
    // Inputs first: a bad camera, video or calibration costs nothing.
    live::FrameInput input =
        a->camera >= 0 ? live::FrameInput::camera(a->camera) : live::FrameInput::video(a->video);
    const auto calib = tracking::loadCalibration(job.calibration);
    calib.forImageSize(input.size());  // refuses another aspect ratio, naming the file
    std::unique_ptr<terrain::Terrain> planet = job.planetFile.empty()
                                                   ? makeDefaultPlanet(job.gridLevel, job.seed)
                                                   : io::loadPlanet(job.planetFile);
    a->settings.options = job.options;
    a->settings.out = job.out;
    const auto r = live::runLive(input, calib, *planet, a->settings);
    std::cout << "live: " << r.frames << " frames, " << r.strokes << " strokes; saved "
              << r.saved.string() << "\n";
    return 0;
  };
});

}  // namespace
}  // namespace ps::app
