// `planetsculpt bench frame`: the whole frame of the AR app, per frame of data/demo.mkv (640x480)
// on the default planet, one thread:
//   track      = marker detection + scene tracking (replay::FrameStepper),
//   edit       = the brush stroke through the edit pipeline (the same stepper),
//   tessellate = the AR view's tessellation (<= 70,000 triangles),
//   render     = PlanetRenderer::renderAR on headless EGL (llvmpipe here) with its read-back,
//   overview   = PlanetRenderer::renderOverview, every 4th frame only (as the live app does).
// Medians over the frames with the planet in view (every frame's in "all_frames"; fps_wall is
// every frame by the wall clock, video decoding included), each stage's share of the summed
// time, and the skips: frames whose view and terrain did not change (the tessellator returned
// its previous mesh, the renderer uploaded nothing). A second line per case ("..._still")
// renders one view repeatedly with nothing changed, showing what a skip costs. Two cases: the
// app's dist_max of 4 px, and a dense view at 0.05 px that runs into the triangle budget. The
// machine (nproc, /proc/loadavg before and after, GL_RENDERER) goes with the figures: on a
// shared 2-core machine the load moves them. Without a headless OpenGL context (or the demo
// video) it prints one line saying so and returns.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>
#include <tuple>

#include "app/build_paths.hpp"
#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/demo_options.hpp"
#include "bench/frame_skips.hpp"
#include "bench/gl_context.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "replay/replay.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/calibration.hpp"
#include "tracking/video.hpp"

namespace ps::bench {

namespace {

constexpr int kOverviewEvery = 4;
constexpr std::size_t kBudget = 70000;

std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

double ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double round3(double v) {
  return std::round(v * 1000) / 1000;
}

Eigen::Matrix3d eigenK(const cv::Matx33d& K) {
  Eigen::Matrix3d k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
  return k;
}

struct Series {
  std::vector<double> track, detect, scene, edit, tessellate, render, overview, total;
  std::vector<double> triangles;     // frames with the planet in view
  std::vector<double> editTouching;  // frames whose tool touched (a stroke stamped)
  double sum(const std::vector<double>& v) const {
    double s = 0;
    for (double x : v) s += x;
    return s;
  }
};

void benchCase(const BenchOptions& options, std::ostream& out, nlohmann::json machine,
               render::EglContext& context, int gridLevel, const std::string& name,
               double kDistMaxPx, render::Shading shading);

void benchFrame(const BenchOptions& options, std::ostream& out) {
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
  for (const auto& [name, distMaxPx, shading] :
       {std::tuple{"demo", 4.0, perPixel}, std::tuple{"demo_faceted", 4.0, faceted},
        std::tuple{"dense", 0.05, perPixel}})
    benchCase(options, out, machine, *context, gridLevel, name, distMaxPx, shading);
}

void benchCase(const BenchOptions& options, std::ostream& out, nlohmann::json machine,
               render::EglContext& context, int gridLevel, const std::string& name,
               double kDistMaxPx, render::Shading shading) {
  render::RenderStyle style;
  style.shading = shading;
  style.boardShadow = style.atmosphere = shading == render::Shading::kPerPixel;
  namespace fs = std::filesystem;
  const fs::path video = ps::app::sourceDir() / "data" / "demo.mkv";
  const fs::path calibPath = ps::app::sourceDir() / "calib" / "synthetic-640x480.yml";
  context.makeCurrent();
  render::PlanetRenderer renderer;
  terrain::Tessellator tessellator;
  machine["load_avg_before"] = loadAverage();
  auto planet = app::makeDefaultPlanet(gridLevel, 1, core::ChartShape::kLatLong);
  tracking::FrameSource source(video);
  const auto calib = tracking::loadCalibration(calibPath).forImageSize(source.size());
  replay::ReplayOptions ro = demoReplayOptions();
  replay::FrameStepper stepper(calib, *planet, ro);
  const double fps = source.fps() > 0 ? source.fps() : ro.fallbackFps;
  const int maxFrames = options.quick ? 90 : 0;
  const Eigen::Matrix3d K = eigenK(calib.K);
  const int W = source.size().width, H = source.size().height;
  terrain::TessellationSettings ts;
  ts.distMaxPx = kDistMaxPx;
  ts.triangleBudget = kBudget;
  // Frames without the planet still draw the camera image: an empty mesh and a camera 1 m in
  // front of the planet (nothing of the planet is drawn).
  const terrain::Mesh empty;
  const terrain::Camera placeholder = render::arCamera(
      Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1), stepper.scale(), K, W, H);

  Series s;      // frames with the planet in view: the figures of the issue
  Series every;  // every frame (the planet hidden behind the tool in most of the demo)
  int frames = 0, planetFrames = 0, reused = 0, noUpload = 0, overviews = 0;
  std::size_t trianglesMax = 0;
  std::optional<terrain::Camera> lastView;
  SkipInputs skips;  // a sample of the views and the edit times, for the skips' line
  std::vector<double> idleEdit;
  cv::Mat image;
  const auto wall0 = std::chrono::steady_clock::now();
  while ((maxFrames == 0 || frames < maxFrames) && source.read(image)) {
    const int frame = source.index();
    const auto r = stepper.step(image, frame, frame / fps);
    double tessMs = 0, renderMs = 0, overviewMs = 0;
    if (r.planetInCamera) {
      const terrain::Camera cam =
          render::arCamera(r.planetInCamera->R, r.planetInCamera->t, stepper.scale(), K, W, H);
      auto t0 = std::chrono::steady_clock::now();
      const terrain::Mesh& mesh = tessellator.tessellate(*planet, cam, ts);
      tessMs = ms(t0);
      ++planetFrames;
      reused += tessellator.stats().reused;
      s.triangles.push_back(double(mesh.triangleCount()));
      trianglesMax = std::max(trianglesMax, mesh.triangleCount());
      std::optional<render::Cursor> cursor;
      if (r.control) cursor = render::Cursor{*r.control, stepper.toolRadius()};
      t0 = std::chrono::steady_clock::now();
      renderer.renderAR(image, *planet, mesh, cam, style, cursor, r.toolTriangles);
      renderMs = ms(t0);
      if (frame % kOverviewEvery == 0) {
        t0 = std::chrono::steady_clock::now();
        renderer.renderOverview(*planet, mesh, cam, 240, 240);
        overviewMs = ms(t0);
        ++overviews;
      }
      lastView = cam;
      if (planetFrames % 8 == 1 && skips.views.size() < 12) {
        skips.views.push_back(cam);
        skips.background = image.clone();
      }
    } else {
      const auto t0 = std::chrono::steady_clock::now();
      renderer.renderAR(image, *planet, empty, lastView ? *lastView : placeholder, style);
      renderMs = ms(t0);
    }
    noUpload += !renderer.stats().uploadedThisFrame;
    if (r.scene.tipValid && !r.touching) idleEdit.push_back(r.times.editMs);
    const double trackMs = r.times.detectMs + r.times.trackMs;
    for (Series* t : {&every, &s}) {
      if (t == &s && !r.planetInCamera) continue;
      t->detect.push_back(r.times.detectMs);
      t->scene.push_back(r.times.trackMs);
      t->track.push_back(trackMs);
      t->edit.push_back(r.times.editMs);
      if (r.touching) t->editTouching.push_back(r.times.editMs);
      t->tessellate.push_back(tessMs);
      t->render.push_back(renderMs);
      t->overview.push_back(overviewMs);
      t->total.push_back(trackMs + r.times.editMs + tessMs + renderMs + overviewMs);
    }
    ++frames;
    if (frames % 30 == 0) std::cerr << "bench frame: " << frames << " frames\r" << std::flush;
  }
  std::cerr << "\n";
  const double wallMs = ms(wall0);
  const double all = s.sum(s.total);
  auto share = [&](const std::vector<double>& v) {
    return all > 0 ? std::round(s.sum(v) / all * 1000) / 1000 : 0.0;
  };
  machine["load_avg_after"] = loadAverage();
  const double medianFrame = median(s.total);
  out << nlohmann::json{{"bench", "frame"},
                        {"case", name},
                        {"video", "data/demo.mkv"},
                        {"size", std::to_string(W) + "x" + std::to_string(H)},
                        {"grid", planet->grid().side()},
                        {"dist_max_px", kDistMaxPx},
                        {"shading",
                         shading == render::Shading::kPerPixel ? "per_pixel" : "faceted"},
                        {"board_shadow_and_rim", style.boardShadow},
                        {"triangle_budget", kBudget},
                        {"frames", frames},
                        {"planet_frames", planetFrames},
                        {"fps", medianFrame > 0 ? std::round(10000 / medianFrame) / 10 : 0},
                        {"fps_wall", wallMs > 0 ? std::round(frames * 10000 / wallMs) / 10 : 0},
                        {"frame_ms", round3(medianFrame)},
                        {"frame_ms_p90", round3(percentile(s.total, 0.9))},
                        {"all_frames",
                         {{"fps", median(every.total) > 0
                                      ? std::round(10000 / median(every.total)) / 10
                                      : 0},
                          {"frame_ms", round3(median(every.total))},
                          {"track_ms", round3(median(every.track))},
                          {"render_ms", round3(median(every.render))}}},
                        {"track_ms", round3(median(s.track))},
                        {"detect_ms", round3(median(s.detect))},
                        {"scene_ms", round3(median(s.scene))},
                        {"edit_ms", round3(median(s.edit))},
                        {"edit_ms_p90", round3(percentile(s.edit, 0.9))},
                        {"edit_ms_touching", round3(median(s.editTouching))},
                        {"touching_frames", s.editTouching.size()},
                        {"tessellate_ms", round3(median(s.tessellate))},
                        {"render_ms", round3(median(s.render))},
                        {"overview_ms_when_drawn",
                         round3(overviews ? s.sum(s.overview) / overviews : 0.0)},
                        {"triangles", std::llround(median(s.triangles))},
                        {"triangles_max", trianglesMax},
                        {"share",
                         {{"track", share(s.track)},
                          {"edit", share(s.edit)},
                          {"tessellate", share(s.tessellate)},
                          {"render", share(s.render)},
                          {"overview", share(s.overview)}}},
                        {"skips",
                         {{"tessellation_reused", reused},
                          {"no_upload", noUpload},
                          {"frames_without_planet", frames - planetFrames},
                          {"overview_every", kOverviewEvery},
                          {"overview_frames", overviews}}},
                        {"machine", machine}}
             .dump()
      << std::endl;

  // The same view again and again, nothing changed: the tessellator hands back its mesh and
  // the renderer uploads nothing; only the drawing and the read-back remain.
  if (lastView) {
    const int repeats = std::max(10, options.repeats * 2);
    std::vector<double> tess, rend;
    int reusedStill = 0;
    const std::size_t uploads0 = renderer.stats().uploads;
    const terrain::Mesh* mesh = nullptr;
    for (int i = 0; i < repeats; ++i) {
      auto t0 = std::chrono::steady_clock::now();
      mesh = &tessellator.tessellate(*planet, *lastView, ts);
      tess.push_back(ms(t0));
      reusedStill += tessellator.stats().reused;
      t0 = std::chrono::steady_clock::now();
      renderer.renderAR(image, *planet, *mesh, *lastView, style);
      rend.push_back(ms(t0));
    }
    out << nlohmann::json{{"bench", "frame"},
                          {"case", name + "_still"},
                          {"repeats", repeats},
                          {"triangles", mesh->triangleCount()},
                          {"tessellate_ms", round3(median(tess))},
                          {"render_ms", round3(median(rend))},
                          {"tessellation_reused", reusedStill},
                          {"uploads", renderer.stats().uploads - uploads0},
                          {"load_avg", loadAverage()}}
               .dump()
        << std::endl;
  }

  // Each skip against doing the work, on views of this replay (the faceted baseline only
  // measures its frame rate).
  if (shading == render::Shading::kFaceted) return;
  std::cerr << "bench frame: skips (" << name << ")\n";
  skips.settings = ts;
  skips.editTouchingMs = median(s.editTouching);
  skips.editIdleMs = median(idleEdit);
  skips.idleFrames = int(idleEdit.size());
  skips.overviewMs = overviews ? s.sum(s.overview) / overviews : 0.0;
  skips.overviewEvery = kOverviewEvery;
  skips.repeats = options.quick ? 2 : 5;
  out << nlohmann::json{{"bench", "frame"},
                        {"case", name + "_skips"},
                        {"grid", planet->grid().side()},
                        {"skips", measureSkips(renderer, *planet, skips)},
                        {"load_avg", loadAverage()}}
             .dump()
      << std::endl;
}

}  // namespace

static const BenchRegistration kRegistered("frame", benchFrame);

}  // namespace ps::bench
