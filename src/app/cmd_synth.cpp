// `planetsculpt synth SCENE --out VIDEO.mkv`: renders a scripted synthetic scene (a built-in
// name or a JSON script, tracking/synth.hpp) into a lossless FFV1 video, with the ground truth
// of every frame as JSON lines in VIDEO.truth.jsonl (a header line with the script and the
// camera, then one line per frame: poses, tool tip, expected control vertex).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "app/build_paths.hpp"
#include "app/command_registry.hpp"
#include "app/progress.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "edit/control_vertex.hpp"
#include "replay/truth_check.hpp"
#include "tracking/synth.hpp"
#include "tracking/video.hpp"

namespace ps::app {

namespace {

struct SynthArgs {
  std::string scene = "board-demo", out, truth;
  int frames = 0;
  long long grid = 2049;
  double touch = 0.004;
  bool grey = false;
  int stillsEvery = 0;
  double noiseScale = 1.0;
};

int runSynth(const SynthArgs& a) {
  tracking::SynthScript script = std::filesystem::exists(a.scene) || a.scene.ends_with(".json")
                                     ? tracking::loadSynthScript(a.scene)
                                     : tracking::builtinScene(a.scene, ps::app::sourceDir());
  if (a.grey) script.colour = false;
  if (!(a.noiseScale >= 0)) throw core::InputError("--noise-scale must be >= 0");
  for (auto& k : script.keys) k.noise *= a.noiseScale;
  if (a.frames > 0) {
    while (script.keys.size() > 1 && script.keys[script.keys.size() - 2].frame >= a.frames - 1)
      script.keys.pop_back();
    if (script.keys.back().frame > a.frames - 1) script.keys.back().frame = a.frames - 1;
  }
  const tracking::SynthRenderer renderer(script);
  const core::LatLongChart chart(core::GridSize::fromSide(a.grid), 1.0);
  const std::filesystem::path out = a.out.empty() ? "synth.mkv" : a.out;
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  const std::filesystem::path truthPath =
      a.truth.empty() ? replay::truthPathFor(out) : std::filesystem::path(a.truth);
  std::ofstream truth(truthPath.string() + ".part");
  if (!truth) throw std::runtime_error("cannot write " + truthPath.string());
  truth << nlohmann::json{{"type", "header"},
                          {"video", out.filename().string()},
                          {"frames", renderer.frames()},
                          {"grid", a.grid},
                          {"touch_distance_m", a.touch},
                          {"script", tracking::toJson(script)}}
               .dump()
        << "\n";
  const std::string partVideo = out.string() + ".part.mkv";
  tracking::LosslessWriter writer(partVideo, script.size, script.fps, script.colour);
  Progress p("synth " + out.filename().string());
  int touching = 0;
  for (int f = 0; f < renderer.frames(); ++f) {
    const cv::Mat image = renderer.render(f);
    writer.write(image);
    if (a.stillsEvery > 0 && f % a.stillsEvery == 0) {
      char name[32];
      std::snprintf(name, sizeof name, "_%04d.png", f);
      const std::string still = out.parent_path() / (out.stem().string() + name);
      if (!cv::imwrite(still, image)) throw std::runtime_error("cannot write " + still);
    }
    const auto t = renderer.truth(f);
    nlohmann::json j = t.toJson();
    j["type"] = "frame";
    j["touching"] = t.tipHeight <= a.touch;
    touching += t.tipHeight <= a.touch;
    if (t.tipPlanet.norm() > 0) {
      const auto cv = edit::nearestVertex(chart, t.tipPlanet);
      j["control_vertex"] = {{"u", cv.u}, {"v", cv.v}};
    }
    truth << j.dump() << "\n";
    p.update(double(f + 1) / renderer.frames(), std::to_string(f + 1) + " frames");
  }
  writer.close();
  truth.close();
  std::filesystem::rename(partVideo, out);
  std::filesystem::rename(truthPath.string() + ".part", truthPath);
  p.done(std::to_string(renderer.frames()) + " frames, " + std::to_string(touching) +
         " touching, " + std::to_string(std::filesystem::file_size(out) >> 10) + " KiB");
  std::cout << "wrote " << out.string() << " and " << truthPath.string() << "\n";
  return 0;
}

const CommandRegistration kSynth([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<SynthArgs>();
  sub = root.add_subcommand("synth",
                            "Render a synthetic marker video (lossless FFV1) with ground truth");
  std::string names;
  for (const auto& n : tracking::builtinSceneNames()) names += (names.empty() ? "" : ", ") + n;
  sub->add_option("scene", a->scene, "Built-in scene (" + names + ") or JSON script")
      ->capture_default_str();
  sub->add_option("--out", a->out, "Output video (.mkv)")->required();
  sub->add_option("--truth", a->truth, "Ground-truth JSON lines (default: VIDEO.truth.jsonl)");
  sub->add_option("--frames", a->frames, "Cut the scene to this many frames");
  sub->add_option("--grid", a->grid, "Planet grid side for the expected control vertex")
      ->capture_default_str();
  sub->add_option("--touch", a->touch, "Touch distance (m) for the ground truth's touching flag")
      ->capture_default_str();
  sub->add_flag("--grey", a->grey, "Write a grey video (smaller)");
  sub->add_option("--noise-scale", a->noiseScale, "Multiply the scene's sensor noise (0: none)")
      ->capture_default_str();
  sub->add_option("--stills", a->stillsEvery, "Also write every Nth frame as VIDEO_NNNN.png");
  return [a] { return runSynth(*a); };
});

}  // namespace
}  // namespace ps::app
