// `planetsculpt bench occlusion` (issue 42, part 1): how exactly what stands in front of the
// planet hides it in the AR view, one row per recording.
//   * The tool (render/occluder_pass.hpp, tracking/tool_shape.hpp): on synthetic recordings of
//     the planet board and the tool cube (tracking/synth.hpp) with the tool passing in front of
//     the planet, the mask of planet pixels the tool hides, as the pipeline draws it (tracked
//     poses -> the renderer's tool depth pass), against the mask the true geometry gives (the
//     true planet and tool poses through the same renderer): IoU (target >= 0.9).
//   * Nothing in front: on the shipped demo's frames (data/demo.mkv, tracked as `demo` tracks
//     it) in which the truth has no tool in front of the planet, the planet's pixels hidden by
//     mistake (target <= 1 %); the demo's frames with the tool in front give its IoU too.
// A mask is the planet's pixels (depth < 1 drawn without the tool) whose depth the tool's
// triangles beat (drawn with it): what the tool hides, whatever the planet's colour.
// Then the hand's rows (bench_occlusion_hand.cpp: the board's appearance model's mask against
// the scenes' geometry), one a recording and pose, "part": "hand".
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <span>
#include <vector>

#include "app/build_paths.hpp"
#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/demo_options.hpp"
#include "bench/gl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "replay/replay.hpp"
#include "replay/truth_check.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/synth.hpp"
#include "tracking/tool_shape.hpp"
#include "tracking/video.hpp"

namespace ps::bench {

namespace {

constexpr double kIoUTarget = 0.9, kFalseHiddenTarget = 0.01;

// A recording: its frames, its ground truth and how the pipeline tracks it.
struct OcclusionRecording {
  std::string name;
  std::string kind;  // "synthetic" (the tool passes in front) or "demo"
  std::shared_ptr<tracking::SynthRenderer> truth;       // the script the frames were made from
  std::function<bool(int frame, cv::Mat& image)> read;  // false at the end
  tracking::CameraCalibration calibration;
  replay::ReplayOptions options;
  int frames = 0;
};

struct Masks {
  cv::Mat planet, hidden;  // CV_8U, 255 where set
};

// What `tool` hides of the planet seen through `camera`.
Masks occlusionMasks(render::PlanetRenderer& renderer, terrain::Tessellator& tessellator,
                     const terrain::Terrain& planet, const terrain::Camera& camera,
                     std::span<const Eigen::Vector3d> tool) {
  terrain::TessellationSettings ts;
  ts.distMaxPx = 1;
  const terrain::Mesh& mesh = tessellator.tessellate(planet, camera, ts);
  renderer.renderAR({}, planet, mesh, camera, {});
  const cv::Mat bare = renderer.readDepth();
  Masks m;
  m.planet = bare < 1.0f;
  if (tool.size() < 3) {
    m.hidden = cv::Mat::zeros(bare.size(), CV_8U);
    return m;
  }
  renderer.renderAR({}, planet, mesh, camera, {}, std::nullopt, tool);
  const cv::Mat with = renderer.readDepth();
  m.hidden = m.planet & (with < bare);
  return m;
}

struct Tally {
  int frames = 0, planetLost = 0;
  // Frames whose truth has the tool in front of the planet.
  int inFront = 0, toolLostInFront = 0;
  double intersection = 0, unionPx = 0, trueHidden = 0, estimatedHidden = 0;
  double trackedIntersection = 0, trackedUnion = 0;  // the frames the tool had a pose
  std::vector<double> frameIoU;
  // Frames whose truth has nothing in front of the planet.
  int nothingInFront = 0, framesWithFalseHides = 0;
  double falseHidden = 0, planetPx = 0, worstFalse = 0;
};

Eigen::Matrix3d eigenOf(const cv::Matx33d& K) {
  Eigen::Matrix3d k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
  return k;
}

Tally measureTool(const OcclusionRecording& rec, int gridLevel, render::PlanetRenderer& renderer) {
  auto planet = app::makeDefaultPlanet(gridLevel, 1, core::ChartShape::kLatLong);
  replay::FrameStepper stepper(rec.calibration, *planet, rec.options);
  const tracking::ToolShape shape = tracking::toolShape(rec.options.scene);
  const Eigen::Matrix3d K = eigenOf(rec.calibration.K);
  const int W = rec.truth->script().size.width, H = rec.truth->script().size.height;
  terrain::Tessellator trueTess, estTess;
  Tally t;
  cv::Mat image;
  const double fps = rec.truth->script().fps;
  for (int frame = 0; frame < rec.frames && rec.read(frame, image); ++frame) {
    const replay::StepResult r = stepper.step(image, frame, frame / fps);
    ++t.frames;
    // The truth: the planet frame has the board's axes at the planet's centre.
    const tracking::FrameTruth truth = rec.truth->truth(frame);
    const tracking::Pose trueP{truth.camera.R, truth.planetCentreCamera};
    const double scale = stepper.scale();
    const terrain::Camera trueCam = render::arCamera(trueP.R, trueP.t, scale, K, W, H);
    const auto trueTool = tracking::toolTriangles(shape, trueP.inverse() * truth.tool, scale);
    const Masks T = occlusionMasks(renderer, trueTess, *planet, trueCam, trueTool);
    const double trueHidden = cv::countNonZero(T.hidden);
    if (!r.planetInCamera) {
      ++t.planetLost;  // no planet drawn, nothing to hide
      continue;
    }
    const terrain::Camera estCam =
        render::arCamera(r.planetInCamera->R, r.planetInCamera->t, scale, K, W, H);
    const Masks E = occlusionMasks(renderer, estTess, *planet, estCam, r.toolTriangles);
    const double estHidden = cv::countNonZero(E.hidden);
    if (trueHidden > 0) {
      ++t.inFront;
      t.toolLostInFront += r.toolTriangles.empty() ? 1 : 0;
      const double inter = cv::countNonZero(T.hidden & E.hidden);
      const double uni = cv::countNonZero(T.hidden | E.hidden);
      t.intersection += inter;
      t.unionPx += uni;
      if (!r.toolTriangles.empty()) {
        t.trackedIntersection += inter;
        t.trackedUnion += uni;
      }
      t.trueHidden += trueHidden;
      t.estimatedHidden += estHidden;
      t.frameIoU.push_back(inter / uni);
    } else {
      ++t.nothingInFront;
      const double planetPx = cv::countNonZero(T.planet);
      t.falseHidden += estHidden;
      t.planetPx += planetPx;
      t.framesWithFalseHides += estHidden > 0 ? 1 : 0;
      if (planetPx > 0) t.worstFalse = std::max(t.worstFalse, estHidden / planetPx);
    }
  }
  return t;
}

nlohmann::json toolRow(const OcclusionRecording& rec, const Tally& t) {
  std::vector<double> ious = t.frameIoU;
  nlohmann::json row = {{"bench", "occlusion"},
                        {"part", "tool"},
                        {"part", "tool"},
                        {"recording", rec.name},
                        {"kind", rec.kind},
                        {"frames", t.frames},
                        {"frames_planet_lost", t.planetLost},
                        {"frames_tool_in_front", t.inFront},
                        {"frames_tool_lost_in_front", t.toolLostInFront},
                        {"frames_nothing_in_front", t.nothingInFront},
                        {"target_iou", kIoUTarget},
                        {"target_false_hidden", kFalseHiddenTarget}};
  if (t.inFront > 0) {
    std::sort(ious.begin(), ious.end());
    row["iou"] = round4OrMinusOne(t.intersection / t.unionPx);  // over all the frames' pixels
    // Over the frames the tracker gave the tool a pose (a tool lost hides nothing).
    row["iou_tool_tracked"] =
        round4OrMinusOne(t.trackedUnion > 0 ? t.trackedIntersection / t.trackedUnion : 0.0);
    row["iou_frame_median"] = round4OrMinusOne(median(ious));
    row["iou_frame_p10"] = round4OrMinusOne(percentile(ious, 0.1));
    row["iou_frame_min"] = round4OrMinusOne(ious.front());
    row["hidden_px_true"] = t.trueHidden;
    row["hidden_px_estimated"] = t.estimatedHidden;
  }
  if (t.nothingInFront > 0) {
    row["false_hidden"] = round4OrMinusOne(t.planetPx > 0 ? t.falseHidden / t.planetPx : 0.0);
    row["false_hidden_frame_max"] = round4OrMinusOne(t.worstFalse);
    row["frames_with_false_hides"] = t.framesWithFalseHides;
    row["planet_px"] = t.planetPx;
  }
  return row;
}

// A synthetic recording on the board with the tool cube: its keys, rendered on demand.
OcclusionRecording synthetic(const std::string& name, std::vector<tracking::SynthKey> keys,
                             std::uint64_t seed) {
  tracking::SynthScript s = tracking::builtinScene("board-sweep", app::sourceDir());
  s.seed = seed;
  s.keys = std::move(keys);
  OcclusionRecording rec;
  rec.name = name;
  rec.kind = "synthetic";
  rec.truth = std::make_shared<tracking::SynthRenderer>(s);
  rec.frames = rec.truth->frames();
  rec.calibration = s.camera;
  rec.options.scene.useBoard(s.board);
  rec.options.scene.useToolLayout(s.toolLayout);
  rec.options.scene.planetRadius = s.planetRadius;
  const auto truth = rec.truth;
  rec.read = [truth](int frame, cv::Mat& image) {
    image = truth->render(frame);
    return true;
  };
  return rec;
}

tracking::SynthKey key(double frame, double camDist, double camElev, double camAz, double tipLat,
                       double tipLon, double tipHeightMm, double tilt, double turn) {
  tracking::SynthKey k;
  k.frame = frame;
  k.camDistance = camDist;
  k.camElevationDeg = camElev;
  k.camAzimuthDeg = camAz;
  k.tipLatDeg = tipLat;
  k.tipLonDeg = tipLon;
  k.tipHeightMm = tipHeightMm;
  k.toolTiltDeg = tilt;
  k.toolTurnDeg = turn;
  return k;
}

// The tool passing in front of the planet: hovering across its face with the camera still, in
// touch while the camera orbits, and leaning toward the camera, the cube large in the image;
// then behind it.
std::vector<OcclusionRecording> syntheticRecordings(bool quick) {
  const double n = quick ? 8 : 48;
  std::vector<OcclusionRecording> out;
  out.push_back(synthetic(
      "tool-hover-across",
      {key(0, 0.55, 40, -90, 20, -125, 15, 25, 0), key(n / 2, 0.55, 40, -90, 45, -90, 15, 25, 10),
       key(n - 1, 0.55, 40, -90, 25, -55, 15, 25, -10)},
      31));
  out.push_back(synthetic(
      "tool-touch-orbit",
      {key(0, 0.5, 35, -115, 35, -115, 0, 45, 0), key(n / 2, 0.5, 50, -90, 45, -85, 2, 45, 15),
       key(n - 1, 0.5, 40, -65, 30, -70, 0, 45, 0)},
      32));
  out.push_back(synthetic(
      "tool-leaning-close",
      {key(0, 0.4, 45, -100, 55, -110, 20, 45, 15), key(n - 1, 0.4, 45, -80, 65, -75, 20, 55, -15)},
      33));
  // Nothing in front: the tool behind the planet (its far side), under a light that dims to
  // 60 % and sensor noise of 3 grey levels.
  std::vector<tracking::SynthKey> behind = {key(0, 0.55, 35, -90, 20, 60, 10, 20, 0),
                                            key(n - 1, 0.55, 35, -80, 35, 110, 10, 20, 0)};
  behind[0].noise = behind[1].noise = 3.0;
  behind[1].gain = 0.6;
  out.push_back(synthetic("tool-behind-dim-noisy", behind, 34));
  return out;
}

// The shipped demo, tracked as `planetsculpt demo` tracks it, with the truth beside it.
OcclusionRecording demoRecording(bool quick) {
  const auto root = app::sourceDir();
  const auto video = root / "data" / "demo.mkv";
  std::ifstream truthFile(replay::truthPathFor(video));
  std::string header;
  std::getline(truthFile, header);
  const auto j = nlohmann::json::parse(header);
  OcclusionRecording rec;
  rec.name = "demo";
  rec.kind = "demo";
  rec.truth = std::make_shared<tracking::SynthRenderer>(
      tracking::parseSynthScript(j.at("script"), "data/demo.truth.jsonl", root / "data"));
  auto source = std::make_shared<tracking::FrameSource>(video);
  rec.calibration = tracking::loadCalibration(root / "calib" / "synthetic-640x480.yml")
                        .forImageSize(source->size());
  rec.options = demoReplayOptions();
  rec.frames = quick ? 40 : rec.truth->frames();
  rec.read = [source](int, cv::Mat& image) { return source->read(image); };
  return rec;
}

}  // namespace

void benchOcclusion(const BenchOptions& o, const HandBenchSettings& hand, std::ostream& out) {
  const auto gl = glContextOrSkip("occlusion", out);
  if (!gl) return;
  render::PlanetRenderer renderer;
  const int gridLevel = o.quick ? 9 : 11;
  std::vector<OcclusionRecording> recordings = syntheticRecordings(o.quick);
  recordings.push_back(demoRecording(o.quick));
  for (const auto& rec : recordings) {
    std::cerr << "bench occlusion: " << rec.name << "\n";
    out << toolRow(rec, measureTool(rec, gridLevel, renderer)).dump() << std::endl;
  }
  benchOcclusionHand(o, hand, out);
}

static const BenchRegistration kOcclusion(
    "occlusion", "The tool and the hand in front of the planet: masks against the truth",
    [](CLI::App& command) -> BenchFunction {
      auto hand = std::make_shared<HandBenchSettings>();
      addHandOptions(command, *hand);
      return [hand](const BenchOptions& o, std::ostream& out) { benchOcclusion(o, *hand, out); };
    });

}  // namespace ps::bench
