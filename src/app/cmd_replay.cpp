// `planetsculpt replay VIDEO --calib FILE --out DIR`: the whole pipeline from a recorded or
// synthetic video with no window (replay/replay.hpp). Writes DIR/heightmap.png (+ .json),
// DIR/planet.planet, DIR/log.jsonl (one line per frame; identical on every replay of the same
// input), DIR/timings.jsonl (times; these differ run to run) and DIR/summary.json.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/command_registry.hpp"
#include "app/default_planet.hpp"
#include "app/progress.hpp"
#include "core/grid.hpp"
#include "core/input_error.hpp"
#include "io/heightmap_export.hpp"
#include "io/planet_file.hpp"
#include "replay/replay.hpp"

namespace ps::app {

namespace {

struct ReplayArgs {
  std::string video, calib, out = "out/replay", planetFile, family = "tag36h11", mode = "raise";
  long long grid = 2049;
  std::uint64_t seed = 1;
  replay::ReplayOptions options;
  std::vector<double> tip = {0.0, -0.08, 0.0};
  double brushRadiusKm = 250, strengthM = 600;
  bool noFilter = false;
};

void renameInto(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::error_code ec;
  std::filesystem::rename(from, to, ec);
  if (ec) throw std::runtime_error("cannot rename " + from.string() + " to " + to.string());
}

int runReplayCommand(ReplayArgs& a) {
  auto& o = a.options;
  o.detector.family = a.family;
  if (a.tip.size() != 3) throw core::InputError("--tip needs three numbers X,Y,Z (metres)");
  o.scene.tipOffset = {a.tip[0], a.tip[1], a.tip[2]};
  o.brush.radius = a.brushRadiusKm * 1e3;
  o.brush.strength = a.strengthM;
  o.brush.mode = edit::brushModeFromString(a.mode);
  if (a.noFilter) o.scene.planet.filter = o.scene.tool.filter = o.scene.filterTip = false;
  o.validate();
  // Inputs first: a bad video or calibration costs nothing.
  tracking::FrameSource source(a.video);
  const auto calib = tracking::loadCalibration(a.calib);
  calib.forImageSize(source.size());  // refuses another aspect ratio, naming the file
  std::unique_ptr<terrain::Terrain> planet;
  if (!a.planetFile.empty())
    planet = io::loadPlanet(a.planetFile);
  else
    planet = makeDefaultPlanet(core::GridSize::fromSide(a.grid).n(), a.seed);

  const std::filesystem::path out(a.out);
  std::filesystem::create_directories(out);
  std::ofstream log(out / "log.jsonl.part"), timings(out / "timings.jsonl.part");
  if (!log || !timings) throw std::runtime_error("cannot write in " + out.string());
  replay::ReplaySummary s;
  {
    Progress p("replay " + std::filesystem::path(a.video).filename().string());
    s = replay::runReplay(source, calib, *planet, o, log, &timings, [&](int f, int total) {
      p.update(total > 0 ? double(f) / total : 0.0, std::to_string(f) + " frames");
    });
    p.done(std::to_string(s.frames) + " frames, " + std::to_string(s.strokes) + " strokes, " +
           std::to_string(s.stamps) + " stamps");
  }
  log.close();
  timings.close();
  renameInto(out / "log.jsonl.part", out / "log.jsonl");
  renameInto(out / "timings.jsonl.part", out / "timings.jsonl");
  {
    Progress p("heightmap");
    const int h = std::min(planet->grid().m(), 4096), w = 2 * h;
    io::writeHeightPng16(io::resampleEquirectangular(*planet, w, h), out / "heightmap.png");
    p.update(0.6);
    io::savePlanet(*planet, out / "planet.planet");
    p.done((out / "heightmap.png").string() + ", planet.planet");
  }
  nlohmann::json summary = {
      {"video", a.video},
      {"calibration", a.calib},
      {"frames", s.frames},
      {"announced_frames", s.announcedFrames},
      {"truncated", s.truncated},
      {"frames_with_planet", s.framesWithPlanet},
      {"frames_with_tool", s.framesWithTool},
      {"frames_with_tip", s.framesWithTip},
      {"touching_frames", s.touchingFrames},
      {"strokes", s.strokes},
      {"stamps", s.stamps},
      {"modified_vertices", s.modifiedVertices},
      {"skipped_frames", s.skippedFrames},
      {"warnings", s.warnings},
      {"grid", planet->grid().label()},
      {"files", {"heightmap.png", "planet.planet", "log.jsonl", "timings.jsonl"}}};
  std::ofstream(out / "summary.json") << summary.dump(2) << "\n";
  for (const auto& w : s.warnings) std::cerr << "replay: warning: " << w << "\n";
  std::cout << "wrote " << (out / "heightmap.png").string()
            << ", planet.planet, log.jsonl, timings.jsonl, summary.json\n";
  return s.frames > 0 ? 0 : 1;
}

const CommandRegistration kReplay([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<ReplayArgs>();
  auto& o = a->options;
  sub =
      root.add_subcommand("replay", "Replay a marker video through tracking and the edit pipeline");
  sub->add_option("video", a->video, "Video (or image folder) to replay")->required();
  sub->add_option("--calib", a->calib, "Camera calibration (OpenCV YAML)")->required();
  sub->add_option("--out", a->out, "Output folder")->capture_default_str();
  sub->add_option("--planet", a->planetFile, "Sculpt this planet file instead of the default");
  sub->add_option("--grid", a->grid, "Default planet's grid side (2^n+1)")->capture_default_str();
  sub->add_option("--seed", a->seed, "Default planet's relief seed")->capture_default_str();
  sub->add_option("--family", a->family, "Marker family")->capture_default_str();
  sub->add_option("--decimate", o.detector.decimate, "AprilTag search decimation")
      ->capture_default_str();
  sub->add_option("--planet-id", o.scene.planet.id, "Planet marker id")->capture_default_str();
  sub->add_option("--planet-marker-size", o.scene.planet.size, "Planet marker edge (m)")
      ->capture_default_str();
  sub->add_option("--planet-radius", o.scene.planetRadius, "Displayed planet radius (m)")
      ->capture_default_str();
  sub->add_option("--tool-id", o.scene.tool.id, "Tool marker id")->capture_default_str();
  sub->add_option("--tool-marker-size", o.scene.tool.size, "Tool marker edge (m)")
      ->capture_default_str();
  sub->add_option("--tip", a->tip, "Tool tip in the tool marker's frame, X,Y,Z (m)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--touch", o.scene.touchDistance, "Touching within this height (m)")
      ->capture_default_str();
  sub->add_option("--brush-radius-km", a->brushRadiusKm, "Brush radius r_d on the planet (km)")
      ->capture_default_str();
  sub->add_option("--strength-m", a->strengthM, "Height change per stamp at the centre (m)")
      ->capture_default_str();
  sub->add_option("--mode", a->mode, "Brush mode: raise, lower or set")->capture_default_str();
  sub->add_option("--max-frames", o.maxFrames, "Stop after this many frames (0: all)");
  sub->add_flag("--no-filter", a->noFilter, "Use raw poses (no One Euro filters)");
  return [a] { return runReplayCommand(*a); };
});

}  // namespace
}  // namespace ps::app
