// `planetsculpt demo`: the README's first command. Replays the bundled demo recording
// (data/demo.mkv, made by `planetsculpt synth demo`) through tracking and the edit pipeline onto
// the default planet, and writes the heightmap, the planet file, the logs and the pictures
// (app/replay_job.hpp). Every replay option works here too (e.g. --tool displace).
#include <iostream>
#include <memory>

#include "app/build_paths.hpp"
#include "app/command_registry.hpp"
#include "app/replay_cli.hpp"

namespace ps::app {
namespace {

// The bundled file, found from the working directory or the source tree.
std::filesystem::path bundled(const std::filesystem::path& relative) {
  if (std::filesystem::exists(relative)) return relative;
  return ps::app::sourceDir() / relative;
}

const CommandRegistration kDemo([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<ReplayCli>();
  a->grid = 4097;
  a->strengthM = 1500;  // bolder than replay's default, so the README pictures show the strokes
  a->job.out = "out/demo";
  a->job.pictures = true;
  a->job.video = bundled("data/demo.mkv");
  a->job.calibration = bundled("calib/synthetic-640x480.yml");
  sub = root.add_subcommand(
      "demo", "Main job: replay the bundled demo recording onto the default planet, with pictures");
  sub->add_option("--video", a->job.video, "Recording to replay")->capture_default_str();
  sub->add_option("--calib", a->job.calibration, "Its camera calibration")->capture_default_str();
  sub->add_option("--out", a->job.out, "Output folder")->capture_default_str();
  sub->add_option("--dist-max", a->job.distMaxPx, "View picture: screen-space error bound (px)")
      ->capture_default_str();
  sub->add_option("--budget", a->job.triangleBudget, "View picture: triangle budget (0: none)")
      ->capture_default_str();
  a->addOptions(sub);
  return [a] {
    a->apply();
    const auto summary = runReplayJob(a->job);
    std::cout << "wrote " << a->job.out.string() << "/: ";
    for (const auto& f : summary["files"]) std::cout << f.get<std::string>() << " ";
    std::cout << "summary.json\n";
    return summary["frames"].get<int>() > 0 ? 0 : 1;
  };
});

}  // namespace
}  // namespace ps::app
