// `planetsculpt bench frame`: the whole frame of the AR app, per frame of data/demo.mkv (640x480)
// on the default planet's relief, on each chart of `--charts` (lat-long and octahedral by default;
// every row names its chart), one thread:
//   track      = marker detection + scene tracking (replay::FrameStepper),
//   edit       = the brush stroke through the edit pipeline (the same stepper),
//   tessellate = the AR view's tessellation (<= 70,000 triangles),
//   hand_mask  = where a hand is in front of the planet: the board's look learned and the mask
//                made (replay::HandOcclusion), the camera image blended over the view there
//                (render::occludeByHand), the live loop's and the AR recorder's path,
//   render     = PlanetRenderer::renderAR on headless EGL (llvmpipe here) with its read-back,
//                the tracked tool's shape drawn into the depth buffer first,
//   overview   = PlanetRenderer::renderOverview, every 4th frame only (as the live app does).
// Medians over the frames with the planet in view (every frame's in "all_frames"; fps_wall is
// every frame by the wall clock, video decoding included), each stage's share of the summed
// time, and the skips: frames whose view and terrain did not change (the tessellator returned
// its previous mesh, the renderer uploaded nothing). A second line per case ("..._still")
// renders one view repeatedly with nothing changed, showing what a skip costs. Two cases: the
// app's dist_max of 4 px, and a dense view at 0.05 px that runs into the triangle budget. The
// machine (nproc, /proc/loadavg before and after, GL_RENDERER) goes with the figures: on a
// shared 2-core machine the load moves them. The frames are undistorted for the renderer and
// the hand mask as the live loop does (a pass-through for the demo's distortion-free
// calibration). `demo_no_hand_mask` is the demo case with the hand mask off (the live panel's
// toggle), run beside it: the mask's share of the frame, measured both ways in one run.
// Without a headless OpenGL context (or the demo video) it prints one line saying so and
// returns.
#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "app/build_paths.hpp"
#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/chart_option.hpp"
#include "bench/demo_options.hpp"
#include "bench/frame_skips.hpp"
#include "bench/gl_context.hpp"
#include "core/chart_factory.hpp"
#include "render/egl_context.hpp"
#include "render/occlusion_composite.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "replay/hand_occlusion.hpp"
#include "replay/replay.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/calibration.hpp"
#include "tracking/undistort.hpp"
#include "tracking/video.hpp"

namespace ps::bench {

namespace {

constexpr int kOverviewEvery = 4;
constexpr std::size_t kBudget = 70000;

double ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

Eigen::Matrix3d eigenK(const cv::Matx33d& K) {
  Eigen::Matrix3d k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
  return k;
}

struct Series {
  std::vector<double> track, detect, scene, edit, handMask, tessellate, render, overview, total;
  std::vector<double> triangles;     // frames with the planet in view
  std::vector<double> editTouching;  // frames whose tool touched (a stroke stamped)
  double sum(const std::vector<double>& v) const {
    double s = 0;
    for (double x : v) s += x;
    return s;
  }
};

struct FrameCase {
  std::string name;
  double distMaxPx;
  render::Shading shading;
  bool handMask = true;  // the live app's default
};

void benchCase(const BenchOptions& options, std::ostream& out, nlohmann::json machine,
               render::EglContext& context, int gridLevel, core::ChartShape chart,
               const FrameCase& frameCase);

void benchFrame(const BenchOptions& options, const ChartChoice& charts, std::ostream& out) {
  namespace fs = std::filesystem;
  nlohmann::json machine = {{"nproc", std::thread::hardware_concurrency()},
                            {"load_avg_before", loadAverage()}};
  const fs::path video = ps::app::sourceDir() / "data" / "demo.mkv";
  const fs::path calibPath = ps::app::sourceDir() / "calib" / "synthetic-640x480.yml";
  const auto context = glContextOrSkip("frame", out, {{"machine", machine}});
  if (!context) return;
  if (!fs::exists(video) || !fs::exists(calibPath)) {
    out << nlohmann::json{{"bench", "frame"},
                          {"skipped", true},
                          {"reason", "missing " + video.string() + " or " + calibPath.string()}}
               .dump()
        << std::endl;
    return;
  }
  machine["gl_renderer"] = context->renderer();
  machine["gl_version"] = context->version();

  const int gridLevel = options.quick ? 11 : 12;  // the demo's planet is 4097^2
  // The app's dist_max (4 px: the demo's planet is ~100 px across, a few hundred triangles) and
  // a dense view that runs into the 70,000-triangle budget (the worst case of the render);
  // both shaded per pixel with the board shadow and the atmosphere rim (the app's defaults), and
  // the demo's also in facets without them (the AR view before per-pixel shading), as the
  // baseline of its frame rate in the same run.
  const auto perPixel = render::Shading::kPerPixel, faceted = render::Shading::kFaceted;
  const std::vector<FrameCase> cases{{"demo", 4.0, perPixel},
                                     {"demo_no_hand_mask", 4.0, perPixel, false},
                                     {"demo_faceted", 4.0, faceted},
                                     {"dense", 0.05, perPixel}};
  for (const core::ChartShape chart : charts.shapes())
    for (const FrameCase& frameCase : cases)
      benchCase(options, out, machine, *context, gridLevel, chart, frameCase);
}

// One case's replay of the demo video: the frame stepper, the AR view's tessellation and render
// and the overview, each timed per frame, with what the case's rows report.
class CaseReplay {
 public:
  CaseReplay(int gridLevel, core::ChartShape chart, const FrameCase& frameCase)
      : handMask_(frameCase.handMask),
        planet_(app::makeDefaultPlanet(gridLevel, 1, chart)),
        source_(ps::app::sourceDir() / "data" / "demo.mkv"),
        calib_(tracking::loadCalibration(ps::app::sourceDir() / "calib" / "synthetic-640x480.yml")
                   .forImageSize(source_.size())),
        ro_(demoReplayOptions()),
        stepper_(calib_, *planet_, ro_),
        undistort_(calib_),
        K_(eigenK(calib_.K)),
        W_(source_.size().width),
        H_(source_.size().height) {
    style_.shading = frameCase.shading;
    style_.boardShadow = style_.atmosphere = frameCase.shading == render::Shading::kPerPixel;
    ts_.distMaxPx = frameCase.distMaxPx;
    ts_.triangleBudget = kBudget;
  }

  // The video's frames (the first `maxFrames`; 0: all).
  void run(int maxFrames) {
    const double fps = source_.fps() > 0 ? source_.fps() : ro_.fallbackFps;
    // Frames without the planet still draw the camera image: an empty mesh and a camera 1 m in
    // front of the planet (nothing of the planet is drawn).
    const terrain::Camera placeholder = render::arCamera(
        Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1), stepper_.scale(), K_, W_, H_);
    const auto wall0 = std::chrono::steady_clock::now();
    while ((maxFrames == 0 || frames_ < maxFrames) && source_.read(raw_)) {
      const int frame = source_.index();
      // As the live loop: tracked as the camera gave it, drawn (and masked) undistorted.
      auto t0 = std::chrono::steady_clock::now();
      image_ = undistort_.apply(raw_);
      const double undistortMs = ms(t0);
      const auto r = stepper_.step(raw_, frame, frame / fps);
      t0 = std::chrono::steady_clock::now();
      handMaskNow_ =
          handOcclusion_.update(handMask_, image_, calib_.K, r.scene.planet, r.planetInCamera,
                                planetRadius(), r.toolTriangles, stepper_.scale());
      const double maskMs = ms(t0);
      StageTimes t = r.planetInCamera ? drawPlanet(r, frame) : drawWithout(placeholder);
      t.undistort = undistortMs;
      t.handMask += maskMs;
      noUpload_ += !renderer_.stats().uploadedThisFrame;
      if (r.scene.tipValid && !r.touching) idleEdit_.push_back(r.times.editMs);
      addTimes(r, t);
      ++frames_;
      if (frames_ % 30 == 0) std::cerr << "bench frame: " << frames_ << " frames\r" << std::flush;
    }
    std::cerr << "\n";
    wallMs_ = ms(wall0);
  }

  // The case's row: medians over the frames with the planet in view, shares, skips.
  nlohmann::json row(const std::string& name, const nlohmann::json& machine) const {
    const double handMasked =
        handMaskedMs_.empty() ? 0.0 : s_.sum(handMaskedMs_) / double(handMaskedMs_.size());
    const double all = s_.sum(s_.total);
    auto share = [&](const std::vector<double>& v) {
      return all > 0 ? std::round(s_.sum(v) / all * 1000) / 1000 : 0.0;
    };
    const double medianFrame = median(s_.total);
    return {{"bench", "frame"},
            {"case", name},
            {"chart", planet_->chart().name()},
            {"video", "data/demo.mkv"},
            {"size", std::to_string(W_) + "x" + std::to_string(H_)},
            {"grid", planet_->grid().side()},
            {"dist_max_px", ts_.distMaxPx},
            {"shading", style_.shading == render::Shading::kPerPixel ? "per_pixel" : "faceted"},
            {"board_shadow_and_rim", style_.boardShadow},
            {"hand_mask", handMask_},
            {"tool_depth_pass", true},
            {"triangle_budget", kBudget},
            {"frames", frames_},
            {"planet_frames", planetFrames_},
            {"fps", medianFrame > 0 ? std::round(10000 / medianFrame) / 10 : 0},
            {"fps_wall", wallMs_ > 0 ? std::round(frames_ * 10000 / wallMs_) / 10 : 0},
            {"frame_ms", round3(medianFrame)},
            {"frame_ms_p90", round3(percentile(s_.total, 0.9))},
            {"all_frames",
             {{"fps", median(every_.total) > 0 ? std::round(10000 / median(every_.total)) / 10 : 0},
              {"frame_ms", round3(median(every_.total))},
              {"track_ms", round3(median(every_.track))},
              {"render_ms", round3(median(every_.render))}}},
            {"track_ms", round3(median(s_.track))},
            {"detect_ms", round3(median(s_.detect))},
            {"scene_ms", round3(median(s_.scene))},
            {"edit_ms", round3(median(s_.edit))},
            {"edit_ms_p90", round3(percentile(s_.edit, 0.9))},
            {"edit_ms_touching", round3(median(s_.editTouching))},
            {"hand_mask_ms", round3(median(s_.handMask))},
            {"hand_mask_ms_p90", round3(percentile(s_.handMask, 0.9))},
            {"hand_mask_ms_mean_masked", round3(handMasked)},
            {"hand_mask_masked_frames", int(handMaskedMs_.size())},
            {"hand_mask_shown_frames", int(handShownPx_.size())},
            {"hand_mask_shown_px", std::llround(median(handShownPx_))},
            {"touching_frames", s_.editTouching.size()},
            {"tessellate_ms", round3(median(s_.tessellate))},
            {"render_ms", round3(median(s_.render))},
            {"overview_ms_when_drawn", round3(overviews_ ? s_.sum(s_.overview) / overviews_ : 0.0)},
            {"triangles", std::llround(median(s_.triangles))},
            {"triangles_max", trianglesMax_},
            {"share",
             {{"track", share(s_.track)},
              {"edit", share(s_.edit)},
              {"hand_mask", share(s_.handMask)},
              {"tessellate", share(s_.tessellate)},
              {"render", share(s_.render)},
              {"overview", share(s_.overview)}}},
            {"skips",
             {{"tessellation_reused", reused_},
              {"no_upload", noUpload_},
              {"frames_without_planet", frames_ - planetFrames_},
              {"overview_every", kOverviewEvery},
              {"overview_frames", overviews_}}},
            {"machine", machine}};
  }

  // The same view again and again, nothing changed: the tessellator hands back its mesh and
  // the renderer uploads nothing; only the drawing and the read-back remain. Nothing when the
  // planet was never in view.
  std::optional<nlohmann::json> stillRow(const std::string& name, int repeats) {
    if (!lastView_) return std::nullopt;
    std::vector<double> tess, rend;
    int reusedStill = 0;
    const std::size_t uploads0 = renderer_.stats().uploads;
    const terrain::Mesh* mesh = nullptr;
    for (int i = 0; i < repeats; ++i) {
      auto t0 = std::chrono::steady_clock::now();
      mesh = &tessellator_.tessellate(*planet_, *lastView_, ts_);
      tess.push_back(ms(t0));
      reusedStill += tessellator_.stats().reused;
      t0 = std::chrono::steady_clock::now();
      renderer_.renderAR(image_, *planet_, *mesh, *lastView_, style_);
      rend.push_back(ms(t0));
    }
    return nlohmann::json{{"bench", "frame"},
                          {"case", name + "_still"},
                          {"chart", planet_->chart().name()},
                          {"repeats", repeats},
                          {"triangles", mesh->triangleCount()},
                          {"tessellate_ms", round3(median(tess))},
                          {"render_ms", round3(median(rend))},
                          {"tessellation_reused", reusedStill},
                          {"uploads", renderer_.stats().uploads - uploads0},
                          {"load_avg", loadAverage()}};
  }

  // Each skip against doing the work, on views of this replay.
  nlohmann::json skipsRow(const std::string& name, int repeats) {
    skips_.settings = ts_;
    skips_.editTouchingMs = median(s_.editTouching);
    skips_.editIdleMs = median(idleEdit_);
    skips_.idleFrames = int(idleEdit_.size());
    skips_.overviewMs = overviews_ ? s_.sum(s_.overview) / overviews_ : 0.0;
    skips_.overviewEvery = kOverviewEvery;
    skips_.repeats = repeats;
    return {{"bench", "frame"},
            {"case", name + "_skips"},
            {"chart", planet_->chart().name()},
            {"grid", planet_->grid().side()},
            {"skips", measureSkips(renderer_, *planet_, skips_)},
            {"load_avg", loadAverage()}};
  }

 private:
  struct StageTimes {
    double undistort = 0, handMask = 0, tessellate = 0, render = 0, overview = 0;
  };

  // The planet's bounding sphere in the board's metres (what the hand mask's silhouette needs).
  double planetRadius() const { return core::boundingRadius(planet_->chart()) / stepper_.scale(); }

  // The planet in view: tessellated, drawn over the frame, the overview every 4th frame.
  StageTimes drawPlanet(const replay::StepResult& r, int frame) {
    StageTimes t;
    const terrain::Camera cam =
        render::arCamera(r.planetInCamera->R, r.planetInCamera->t, stepper_.scale(), K_, W_, H_);
    auto t0 = std::chrono::steady_clock::now();
    // The sand TIN's region at its own detail, as the live loop (none with the demo's brush).
    const terrain::Mesh& mesh = spliced_.view(tessellator_.tessellate(*planet_, cam, ts_),
                                              stepper_.viewPatch(), planet_->chart());
    t.tessellate = ms(t0);
    ++planetFrames_;
    reused_ += tessellator_.stats().reused;
    s_.triangles.push_back(double(mesh.triangleCount()));
    trianglesMax_ = std::max(trianglesMax_, mesh.triangleCount());
    std::optional<render::Cursor> cursor;
    if (r.control) cursor = render::Cursor{*r.control, stepper_.toolRadius()};
    t0 = std::chrono::steady_clock::now();
    // The tool's shape into the depth buffer first (the occluders), then the planet.
    const cv::Mat view =
        renderer_.renderAR(image_, *planet_, mesh, cam, style_, cursor, r.toolTriangles);
    t.render = ms(t0);
    t0 = std::chrono::steady_clock::now();
    const cv::Mat shown = render::occludeByHand(view, image_, handMaskNow_, cam, r.toolTriangles);
    t.handMask = ms(t0);
    if (!shown.empty()) handShownPx_.push_back(cv::countNonZero(handMaskNow_ > 0.5f));
    if (frame % kOverviewEvery == 0) {
      t0 = std::chrono::steady_clock::now();
      renderer_.renderOverview(*planet_, mesh, cam, 240, 240);
      t.overview = ms(t0);
      ++overviews_;
    }
    lastView_ = cam;
    if (planetFrames_ % 8 == 1 && skips_.views.size() < 12) {
      skips_.views.push_back(cam);
      skips_.background = image_.clone();
    }
    return t;
  }

  // No planet in view: the camera image alone, through the renderer.
  StageTimes drawWithout(const terrain::Camera& placeholder) {
    StageTimes t;
    const auto t0 = std::chrono::steady_clock::now();
    renderer_.renderAR(image_, *planet_, empty_, lastView_ ? *lastView_ : placeholder, style_);
    t.render = ms(t0);
    return t;
  }

  void addTimes(const replay::StepResult& r, const StageTimes& t) {
    // Undistorting is part of the live loop's tracking step (a pass-through here).
    const double trackMs = r.times.detectMs + r.times.trackMs + t.undistort;
    if (handOcclusion_.lastMs() > 0) handMaskedMs_.push_back(t.handMask);
    for (Series* series : {&every_, &s_}) {
      if (series == &s_ && !r.planetInCamera) continue;
      series->detect.push_back(r.times.detectMs);
      series->scene.push_back(r.times.trackMs);
      series->track.push_back(trackMs);
      series->edit.push_back(r.times.editMs);
      series->handMask.push_back(t.handMask);
      if (r.touching) series->editTouching.push_back(r.times.editMs);
      series->tessellate.push_back(t.tessellate);
      series->render.push_back(t.render);
      series->overview.push_back(t.overview);
      series->total.push_back(trackMs + r.times.editMs + t.handMask + t.tessellate + t.render +
                              t.overview);
    }
  }

  bool handMask_;  // the case's: the hand mask on (the live app's default) or off
  render::RenderStyle style_;
  render::PlanetRenderer renderer_;
  terrain::Tessellator tessellator_;
  terrain::SplicedView spliced_;  // the sand TIN's region in the view (the live loop's)
  std::unique_ptr<terrain::Terrain> planet_;
  tracking::FrameSource source_;
  tracking::CameraCalibration calib_;
  replay::ReplayOptions ro_;
  replay::FrameStepper stepper_;
  tracking::FrameUndistorter undistort_;
  replay::HandOcclusion handOcclusion_;  // the live loop's hand mask
  cv::Mat handMaskNow_;                  // this frame's (empty: nothing in front)
  Eigen::Matrix3d K_;
  int W_, H_;
  terrain::TessellationSettings ts_;
  const terrain::Mesh empty_;

  Series s_;      // frames with the planet in view: the figures of the issue
  Series every_;  // every frame (the planet hidden behind the tool in most of the demo)
  int frames_ = 0, planetFrames_ = 0, reused_ = 0, noUpload_ = 0, overviews_ = 0;
  std::size_t trianglesMax_ = 0;
  std::optional<terrain::Camera> lastView_;
  SkipInputs skips_;  // a sample of the views and the edit times, for the skips' line
  std::vector<double> idleEdit_;
  cv::Mat raw_;                       // the frame last read, tracked
  cv::Mat image_;                     // undistorted, drawn over
  std::vector<double> handMaskedMs_;  // the hand mask's time in the frames that masked
  // Per frame that showed the camera image over part of the planet: its pixels (mask > 0.5).
  std::vector<double> handShownPx_;
  double wallMs_ = 0;
};

void benchCase(const BenchOptions& options, std::ostream& out, nlohmann::json machine,
               render::EglContext& context, int gridLevel, core::ChartShape chart,
               const FrameCase& frameCase) {
  const std::string& name = frameCase.name;
  context.makeCurrent();
  machine["load_avg_before"] = loadAverage();
  CaseReplay replay(gridLevel, chart, frameCase);
  replay.run(options.quick ? 90 : 0);
  machine["load_avg_after"] = loadAverage();
  out << replay.row(name, machine).dump() << std::endl;
  if (const auto still = replay.stillRow(name, std::max(10, options.repeats * 2)))
    out << still->dump() << std::endl;
  // The faceted baseline and the hand mask's off case only measure their frame rates.
  if (frameCase.shading == render::Shading::kFaceted || !frameCase.handMask) return;
  std::cerr << "bench frame: skips (" << core::toString(chart) << " " << name << ")\n";
  out << replay.skipsRow(name, options.quick ? 2 : 5).dump() << std::endl;
}

}  // namespace

static const BenchRegistration kFrame(
    "frame", "The AR app's whole frame on data/demo.mkv: track, edit, tessellate, render",
    [](CLI::App& command) -> BenchFunction {
      auto charts = std::make_shared<ChartChoice>();
      addChartsOption(command, *charts);
      return [charts](const BenchOptions& o, std::ostream& out) { benchFrame(o, *charts, out); };
    });

}  // namespace ps::bench
