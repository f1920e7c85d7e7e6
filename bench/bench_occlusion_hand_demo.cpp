// `bench occlusion`'s hand row on the shipped demo (data/demo.mkv, issue 42: "the planet's pixels
// hidden by mistake <= 1 %" on the demo's frames without anything in front): each frame tracked
// as `demo` tracks it, the hand mask made by replay::HandOcclusion and cleared over the tracked
// tool by render::occludeByHand (the AR recorder's path), then what it shows over the planet
// (soft mask >= 0.5, within the true planet's sphere) sorted by what the demo's truth
// (data/demo.truth.jsonl: its script, rendered by tracking::SynthRenderer) has there:
//   * hand_in_front / tool_in_front: the hand's disc or the tool's true shape (the cube and its
//     stick, tracking/tool_shape.hpp) nearer the camera than the planet's sphere: right to show;
//   * hand_behind: the synthetic hand is drawn over everything, but its disc is behind the
//     sphere there (a hand lower than the planet's top): the image cannot tell;
//   * tool_edge: within kToolEdgePx of the tool's drawn silhouette (its blurred, anti-aliased
//     edges, motion blur) but not the tool in front;
//   * board: nothing there but the board and the table: a false hide of the mask's own.
// false_hidden pools everything shown but not in front (all but the first class) over the
// planet's pixels in every frame the mask ran; hidden_by_mistake is the same over the frames with
// nothing in front of the planet nor drawn over it (the target, <= 1 %); iou: the shown
// pixels against the hand in front, over the frames it covers >= 0.5 % of the planet (the other
// hand rows' measure; the hand drawn behind the sphere lowers it).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <span>

#include "app/build_paths.hpp"
#include "app/default_planet.hpp"
#include "app/progress.hpp"
#include "bench/bench_util.hpp"
#include "bench/demo_options.hpp"
#include "bench/occlusion_hand_demo.hpp"
#include "core/chart_factory.hpp"
#include "render/occlusion_composite.hpp"
#include "render/projection.hpp"
#include "replay/hand_occlusion.hpp"
#include "replay/truth_check.hpp"
#include "tracking/synth.hpp"
#include "tracking/tool_shape.hpp"
#include "tracking/undistort.hpp"
#include "tracking/video.hpp"

namespace ps::bench {

namespace {

constexpr int kToolEdgePx = 4;

// The ray through pixel (u, v) of pinhole K, z = 1.
Eigen::Vector3d rayOf(const cv::Matx33d& K, double u, double v) {
  return {(u - K(0, 2)) / K(0, 0), (v - K(1, 2)) / K(1, 1), 1.0};
}

// The nearer hit of ray t·d (z = 1 rays: t is the depth) with the sphere, or +inf.
double sphereDepth(const Eigen::Vector3d& d, const Eigen::Vector3d& c, double r) {
  const double dd = d.squaredNorm(), dc = d.dot(c), disc = dc * dc - dd * (c.squaredNorm() - r * r);
  if (disc < 0 || dc <= 0) return std::numeric_limits<double>::infinity();
  return (dc - std::sqrt(disc)) / dd;
}

// The tool's triangles (camera frame, m) drawn: `drawn` where any covers the pixel, `inFront`
// where the nearest one is nearer than the planet's sphere (centre c, radius r).
void rasteriseTool(std::span<const Eigen::Vector3d> tris, const cv::Matx33d& K,
                   const Eigen::Vector3d& c, double r, cv::Mat& drawn, cv::Mat& inFront) {
  const cv::Rect image(0, 0, drawn.cols, drawn.rows);
  for (std::size_t i = 0; i + 2 < tris.size(); i += 3) {
    const Eigen::Vector3d &a = tris[i], &b = tris[i + 1], &e = tris[i + 2];
    if (a.z() <= 1e-4 || b.z() <= 1e-4 || e.z() <= 1e-4) continue;
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const Eigen::Vector3d* p : {&a, &b, &e}) {
      const double u = K(0, 0) * p->x() / p->z() + K(0, 2), v = K(1, 1) * p->y() / p->z() + K(1, 2);
      x0 = std::min(x0, u), x1 = std::max(x1, u), y0 = std::min(y0, v), y1 = std::max(y1, v);
    }
    const cv::Rect box =
        cv::Rect(int(std::floor(x0)), int(std::floor(y0)), int(std::ceil(x1) - std::floor(x0)) + 1,
                 int(std::ceil(y1) - std::floor(y0)) + 1) &
        image;
    const Eigen::Vector3d n = (b - a).cross(e - a);
    for (int v = box.y; v < box.br().y; ++v)
      for (int u = box.x; u < box.br().x; ++u) {
        const Eigen::Vector3d d = rayOf(K, u, v);
        const double nd = n.dot(d);
        if (std::abs(nd) < 1e-15) continue;
        const double t = n.dot(a) / nd;
        if (!(t > 0)) continue;
        const Eigen::Vector3d p = t * d;
        // Inside when p is on the same side of each edge as the normal.
        if (n.dot((b - a).cross(p - a)) < 0 || n.dot((e - b).cross(p - b)) < 0 ||
            n.dot((a - e).cross(p - e)) < 0)
          continue;
        drawn.at<uchar>(v, u) = 255;
        if (t < sphereDepth(d, c, r)) inFront.at<uchar>(v, u) = 255;
      }
  }
}

// The pixels the hand's disc of key k is drawn over (whatever is behind it).
cv::Mat handDrawn(const tracking::SynthScript& s, const tracking::SynthKey& k,
                  const tracking::Pose& camera) {
  cv::Mat out = cv::Mat::zeros(s.size, CV_8U);
  if (!(k.handRadius > 0)) return out;
  std::vector<cv::Point> poly;
  for (int i = 0; i < 96; ++i) {
    const double a = 2 * std::numbers::pi * i / 96;
    const Eigen::Vector3d p = camera.apply(
        {k.handX + k.handRadius * std::cos(a), k.handY + k.handRadius * std::sin(a), k.handHeight});
    if (p.z() <= 1e-4) return out;
    const cv::Matx33d& K = s.camera.K;
    poly.emplace_back(int(std::lround(K(0, 0) * p.x() / p.z() + K(0, 2))),
                      int(std::lround(K(1, 1) * p.y() / p.z() + K(1, 2))));
  }
  cv::fillPoly(out, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(255));
  return out;
}

struct DemoTally {
  int frames = 0, masked = 0, framesShowing = 0, clearFrames = 0, clearFramesShowing = 0;
  int framesWithFalse = 0, worstFrame = -1;
  double planetPx = 0, shownPx = 0, handFront = 0, toolFront = 0, handBehind = 0, toolEdge = 0,
         board = 0, worstFalse = 0, clearPlanetPx = 0, clearShownPx = 0, clearWorst = 0;
  double inter = 0, uni = 0;  // shown against the hand in front, frames it covers >= 0.5 %
  std::vector<double> shownPerFrame;
};

struct FrameClasses {
  cv::Mat planet, shown, front, handBehind, toolEdge, board;
};

// One masked frame's pixels sorted into the classes, added to `t`.
FrameClasses classify(const cv::Mat& mask, const cv::Mat& planet, const cv::Mat& handFront,
                      const cv::Mat& handDrawnPx, const cv::Mat& toolDrawn,
                      const cv::Mat& toolFront, int frame, DemoTally& t) {
  FrameClasses c;
  c.planet = planet;
  c.shown = (mask >= 0.5f) & planet;
  c.front = (handFront | toolFront) & planet;
  const cv::Mat notFront = ~c.front;
  c.handBehind = handDrawnPx & planet & notFront;
  cv::Mat near;
  cv::dilate(toolDrawn, near,
             cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                       cv::Size(2 * kToolEdgePx + 1, 2 * kToolEdgePx + 1)));
  c.toolEdge = near & planet & notFront & ~c.handBehind;
  c.board = planet & notFront & ~c.handBehind & ~c.toolEdge;
  const double planetPx = cv::countNonZero(planet), shown = cv::countNonZero(c.shown);
  t.planetPx += planetPx;
  t.shownPx += shown;
  t.framesShowing += shown > 0 ? 1 : 0;
  if (shown > 0) t.shownPerFrame.push_back(shown);
  t.handFront += cv::countNonZero(c.shown & handFront & planet);
  t.toolFront += cv::countNonZero(c.shown & toolFront & planet & ~handFront);
  t.handBehind += cv::countNonZero(c.shown & c.handBehind);
  t.toolEdge += cv::countNonZero(c.shown & c.toolEdge);
  t.board += cv::countNonZero(c.shown & c.board);
  const double falsePx = cv::countNonZero(c.shown & notFront);
  t.framesWithFalse += falsePx > 0 ? 1 : 0;
  if (planetPx > 0 && falsePx / planetPx > t.worstFalse) {
    t.worstFalse = falsePx / planetPx;
    t.worstFrame = frame;
  }
  const double handPx = cv::countNonZero(handFront & planet);
  if (handPx >= 0.005 * planetPx && handPx > 0) {
    t.inter += cv::countNonZero(c.shown & handFront);
    t.uni += cv::countNonZero(c.shown | (handFront & planet));
  }
  if (cv::countNonZero(c.front | c.handBehind) == 0) {
    ++t.clearFrames;
    t.clearFramesShowing += shown > 0 ? 1 : 0;
    t.clearPlanetPx += planetPx;
    t.clearShownPx += shown;
    if (planetPx > 0) t.clearWorst = std::max(t.clearWorst, shown / planetPx);
  }
  return c;
}

// The frame with the classes painted (the shown pixels' class in full, the rest faint).
void writeDebug(const std::string& dir, int frame, const cv::Mat& image, const FrameClasses& c) {
  cv::Mat shown;
  if (image.channels() == 1)
    cv::cvtColor(image, shown, cv::COLOR_GRAY2BGR);
  else
    shown = image.clone();
  const auto paint = [&](const cv::Mat& where, cv::Scalar colour) {
    shown.setTo(colour, where & c.shown);
  };
  paint(c.front, {0, 200, 0});         // green: right to show
  paint(c.handBehind, {200, 0, 200});  // magenta: the hand behind the sphere
  paint(c.toolEdge, {255, 128, 0});    // blue: the tool's edges
  paint(c.board, {0, 0, 255});         // red: a false hide on the board
  std::vector<std::vector<cv::Point>> outline;
  cv::findContours(c.planet.clone(), outline, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::drawContours(shown, outline, -1, cv::Scalar(255, 255, 0), 1);
  // The planet and what is around it, three times enlarged.
  const cv::Rect box = cv::boundingRect(c.planet);
  const cv::Rect around = cv::Rect(box.x - 40, box.y - 40, box.width + 80, box.height + 80) &
                          cv::Rect(0, 0, shown.cols, shown.rows);
  cv::Mat enlarged;
  cv::resize(shown(around), enlarged, cv::Size(), 3, 3, cv::INTER_NEAREST);
  char name[64];
  std::snprintf(name, sizeof name, "/occlusion_hand_demo_%03d.png", frame);
  std::filesystem::create_directories(dir);
  cv::imwrite(dir + name, enlarged);
}

nlohmann::json demoRow(const DemoTally& t) {
  const double planet = std::max(1.0, t.planetPx);
  const double falsePx = t.shownPx - t.handFront - t.toolFront;
  return {{"bench", "occlusion"},
          {"part", "hand"},
          {"recording", "demo"},
          {"pose", "tracked"},
          {"frames", t.frames},
          {"frames_with_pose", t.masked},
          {"frames_masked", t.masked},
          {"frames_showing", t.framesShowing},
          {"shown_px_median", round4OrMinusOne(median(t.shownPerFrame))},
          {"planet_px", t.planetPx},
          {"shown_px", t.shownPx},
          {"shown_hand_in_front_px", t.handFront},
          {"shown_tool_in_front_px", t.toolFront},
          {"shown_hand_behind_px", t.handBehind},
          {"shown_tool_edge_px", t.toolEdge},
          {"shown_board_px", t.board},
          {"false_hidden", round4OrMinusOne(falsePx / planet)},
          {"false_hidden_board", round4OrMinusOne(t.board / planet)},
          {"false_hidden_frame_max", round4OrMinusOne(t.worstFalse)},
          {"false_hidden_worst_frame", t.worstFrame},
          {"frames_with_false_hides", t.framesWithFalse},
          {"iou", round4OrMinusOne(t.uni > 0 ? t.inter / t.uni : -1)},
          {"clear_frames", t.clearFrames},
          {"clear_frames_showing", t.clearFramesShowing},
          {"hidden_by_mistake", round4OrMinusOne(t.clearShownPx / std::max(1.0, t.clearPlanetPx))},
          {"hidden_by_mistake_worst_frame", round4OrMinusOne(t.clearWorst)},
          {"target_hidden_by_mistake", 0.01}};
}

}  // namespace

void benchOcclusionHandDemo(const BenchOptions& o, const tracking::HandMaskConfig& config,
                            std::ostream& out) {
  const auto root = app::sourceDir();
  const auto video = root / "data" / "demo.mkv";
  std::ifstream truthFile(replay::truthPathFor(video));
  std::string header;
  std::getline(truthFile, header);
  const tracking::SynthRenderer truth(tracking::parseSynthScript(
      nlohmann::json::parse(header).at("script"), "data/demo.truth.jsonl", root / "data"));
  const tracking::SynthScript& script = truth.script();
  tracking::FrameSource source(video);
  const tracking::CameraCalibration calib =
      tracking::loadCalibration(root / "calib" / "synthetic-640x480.yml")
          .forImageSize(source.size());
  const replay::ReplayOptions ro = demoReplayOptions();
  auto planet = app::makeDefaultPlanet(o.quick ? 9 : 10, 1);
  replay::FrameStepper stepper(calib, *planet, ro);
  const tracking::FrameUndistorter undistort(calib);
  replay::HandOcclusion occlusion(config);
  const tracking::ToolShape shape = tracking::toolShape(ro.scene);
  const cv::Matx33d& K = calib.K;
  Eigen::Matrix3d k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
  const int frames = o.quick ? 120 : truth.frames();
  DemoTally t;
  app::Progress progress("occlusion-hand demo");
  cv::Mat frame;
  for (int f = 0; f < frames && source.read(frame); ++f) {
    const replay::StepResult r = stepper.step(frame, f, f / script.fps);
    ++t.frames;
    const cv::Mat image = undistort.apply(frame);
    const double radius = core::boundingRadius(planet->chart()) / stepper.scale();
    cv::Mat mask = occlusion.update(true, image, K, r.scene.planet, r.planetInCamera, radius,
                                    r.toolTriangles, stepper.scale());
    progress.update(double(f + 1) / frames);
    if (!r.planetInCamera || !replay::HandOcclusion::masks(r.scene.planet, r.planetInCamera))
      continue;
    ++t.masked;
    const terrain::Camera cam = render::arCamera(r.planetInCamera->R, r.planetInCamera->t,
                                                 stepper.scale(), k, image.cols, image.rows);
    // The AR frame's last step, on a blank view: the mask is cleared over the tracked tool.
    render::occludeByHand(cv::Mat::zeros(image.size(), CV_8UC3), image, mask, cam, r.toolTriangles);
    if (mask.empty()) mask = cv::Mat::zeros(image.size(), CV_32F);
    const tracking::FrameTruth ft = truth.truth(f);
    const Eigen::Vector3d& c = ft.planetCentreCamera;
    const cv::Mat planetPx = tracking::sphereSilhouette(image.size(), K, c, script.planetRadius);
    const tracking::SynthKey key = truth.keyAt(f);
    cv::Mat toolDrawn = cv::Mat::zeros(image.size(), CV_8U), toolFront = toolDrawn.clone();
    rasteriseTool(tracking::toolTriangles(shape, ft.tool), K, c, script.planetRadius, toolDrawn,
                  toolFront);
    const FrameClasses classes =
        classify(mask, planetPx, tracking::handInFrontOfPlanet(script, key, ft.camera),
                 handDrawn(script, key, ft.camera), toolDrawn, toolFront, f, t);
    if (!o.outDir.empty() && cv::countNonZero(classes.shown) > 0 && f % 5 == 0)
      writeDebug(o.outDir, f, image, classes);
  }
  progress.done(std::to_string(t.frames) + " frames");
  out << demoRow(t).dump() << std::endl;
}

}  // namespace ps::bench
