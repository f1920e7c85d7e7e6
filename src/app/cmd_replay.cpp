// `planetsculpt replay VIDEO --calib FILE --out DIR`: the whole pipeline from a recorded or
// synthetic video with no window (replay/replay.hpp, app/replay_job.hpp). Writes
// DIR/heightmap.png (+ .json), DIR/planet.planet, DIR/log.jsonl (one line per frame; identical
// on every replay of the same input), DIR/timings.jsonl (times; these differ run to run),
// DIR/summary.json, and with --pictures the relief, close-up and view pictures.
#include <iostream>
#include <memory>

#include "app/command_registry.hpp"
#include "app/replay_cli.hpp"

namespace ps::app {
namespace {

const CommandRegistration kReplay([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<ReplayCli>();
  sub =
      root.add_subcommand("replay", "Replay a marker video through tracking and the edit pipeline");
  sub->add_option("video", a->job.video, "Video (or image folder) to replay")->required();
  sub->add_option("--calib", a->job.calibration, "Camera calibration (OpenCV YAML)")->required();
  sub->add_option("--out", a->job.out, "Output folder")->capture_default_str();
  sub->add_flag("--pictures", a->job.pictures,
                "Also write relief, close-up, view and AR showcase pictures");
  sub->add_flag("--render", a->job.render, "Write the AR frames and overviews to OUT/ar/");
  sub->add_option("--render-every", a->job.renderEvery, "Render every Nth frame")
      ->capture_default_str();
  auto* session = sub->add_option("--session", a->job.session,
                                  "A live session's settings sidecar (default: "
                                  "VIDEO.session.jsonl when it exists): its settings, changes, "
                                  "undos and redos are applied at their frames and win over the "
                                  "tool and marker options");
  sub->add_flag("--no-session", a->job.noSession, "Ignore a session sidecar beside the video")
      ->excludes(session);
  a->addOptions(sub);
  return [a] {
    a->apply();
    const auto summary = runReplayJob(a->job);
    std::cout << "wrote " << (a->job.out / "heightmap.png").string() << " and "
              << summary["files"].size() - 1 << " more files, summary.json\n";
    return summary["frames"].get<int>() > 0 ? 0 : 1;
  };
});

}  // namespace
}  // namespace ps::app
