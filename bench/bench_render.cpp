// `planetsculpt bench render`: what per-pixel shading buys. The same views (orbit, 1,000 km up,
// 100 km up, the AR demo's size of planet) at dist_max 1, 4 and 16 px, shaded per pixel and in
// facets, each compared with a reference of the same view (dist_max 0.1 px, no budget, per
// pixel: the full-resolution surface as the shader shows it) and with its own shading's
// reference: SSIM and the mean absolute colour difference over the planet's pixels, the
// triangles, the render's time (median of repeats of an unchanged mesh, read-back included) and
// the height texture's bytes. One JSON row per chart (`--charts`: lat-long and octahedral by
// default, the same relief and grid), view, dist_max and shading.
#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "bench/chart_option.hpp"
#include "bench/gl_context.hpp"
#include "render/egl_context.hpp"
#include "render/image_compare.hpp"
#include "render/planet_renderer.hpp"
#include "terrain/tessellator.hpp"

namespace ps::bench {

namespace {

struct RenderView {
  std::string name;
  terrain::Camera camera;
};

std::vector<RenderView> views(double R, int w, int h) {
  using Eigen::Vector3d;
  const double fov = 2 * std::atan(0.5 * h / 600.0);  // the demo camera's 600 px focal length
  auto look = [&](const Vector3d& eye, const Vector3d& at) {
    return terrain::Camera::lookAt(eye, at, Vector3d::UnitZ(), w, h, fov);
  };
  const Vector3d d = Vector3d(1, 0.2, 0.3).normalized(), ahead = Vector3d(1, 0.4, 0.3).normalized();
  return {{"orbit", look(3.2 * R * Vector3d(1, 0.3, 0.4).normalized(), Vector3d::Zero())},
          {"1000 km", look((R + 1.0e6) * d, R * ahead)},
          {"100 km", look((R + 1.0e5) * d, R * Vector3d(1, 0.24, 0.3).normalized())},
          // The AR demo's planet: about 100 px across in a 640x480 frame.
          {"ar-demo", look(12.0 * R * Vector3d(1, -0.4, 0.6).normalized(), Vector3d::Zero())}};
}

}  // namespace

// One chart's planet: every view, dist_max and shading against the view's references.
void benchRenderOn(core::ChartShape shape, const BenchOptions& o, const std::string& glRenderer,
                   std::ostream& out) {
  const int level = o.quick ? 10 : 12;
  const auto planet = app::makeDefaultPlanet(level, 1, shape);
  const double R = planet->chart().sphereRadius();
  render::PlanetRenderer renderer;
  const int repeats = o.quick ? 3 : 9;
  auto draw = [&](const terrain::Camera& cam, double distMaxPx, render::Shading shading, double* ms,
                  std::size_t* triangles) {
    terrain::Tessellator tess;
    terrain::TessellationSettings ts;
    ts.distMaxPx = distMaxPx;
    ts.triangleBudget = 0;
    const auto& mesh = tess.tessellate(*planet, cam, ts);
    render::RenderStyle style;
    style.shading = shading;
    cv::Mat image = renderer.renderAR({}, *planet, mesh, cam, style);
    std::vector<double> times;
    for (int k = 0; ms && k < repeats; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      image = renderer.renderAR({}, *planet, mesh, cam, style);
      times.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    if (ms) *ms = median(times);
    if (triangles) *triangles = mesh.triangleCount();
    return image;
  };
  for (const auto& v : views(R, 640, 480)) {
    if (o.quick && v.name == "100 km") continue;
    std::cerr << "bench render: " << planet->chart().name() << " " << v.name << "\n";
    const cv::Mat perPixelRef = draw(v.camera, 0.1, render::Shading::kPerPixel, nullptr, nullptr);
    const cv::Mat facetedRef = draw(v.camera, 0.1, render::Shading::kFaceted, nullptr, nullptr);
    for (double px : {1.0, 4.0, 16.0}) {
      for (auto shading : {render::Shading::kFaceted, render::Shading::kPerPixel}) {
        double ms = 0;
        std::size_t triangles = 0;
        const cv::Mat image = draw(v.camera, px, shading, &ms, &triangles);
        const cv::Mat mask = render::drawnMask(image, perPixelRef, {0, 0, 0});
        const auto full = render::compareImages(image, perPixelRef, mask);
        const auto own = render::compareImages(
            image, shading == render::Shading::kPerPixel ? perPixelRef : facetedRef, mask);
        auto r3 = [](double x) { return std::round(x * 1e3) / 1e3; };
        out << nlohmann::json{{"bench", "render"},
                              {"chart", planet->chart().name()},
                              {"view", v.name},
                              {"grid", planet->grid().label()},
                              {"size", "640x480"},
                              {"dist_max_px", px},
                              {"shading",
                               shading == render::Shading::kPerPixel ? "per_pixel" : "faceted"},
                              {"ssim", r3(full.ssim)},
                              {"mean_abs_diff", r3(full.meanAbsDiff)},
                              {"ssim_own_shading", r3(own.ssim)},
                              {"mean_abs_diff_own_shading", r3(own.meanAbsDiff)},
                              {"planet_pixels", full.pixels},
                              {"triangles", triangles},
                              {"ms", r3(ms)},
                              {"texture_bytes", shading == render::Shading::kPerPixel
                                                    ? renderer.stats().heightTextureBytes
                                                    : 0},
                              {"height_tiles_needed", shading == render::Shading::kPerPixel
                                                          ? renderer.stats().heightTilesNeeded
                                                          : 0},
                              {"gl_renderer", glRenderer}}
                   .dump()
            << std::endl;
      }
    }
  }
}

void benchRender(const BenchOptions& o, const ChartChoice& charts, std::ostream& out) {
  const auto gl = glContextOrSkip("render", out);
  if (!gl) return;
  for (const core::ChartShape shape : charts.shapes()) benchRenderOn(shape, o, gl->renderer(), out);
}

namespace {
const BenchRegistration kRender("render",
                                "Per-pixel shading against facets: SSIM, triangles, render time",
                                [](CLI::App& command) -> BenchFunction {
                                  auto charts = std::make_shared<ChartChoice>();
                                  addChartsOption(command, *charts);
                                  return [charts](const BenchOptions& o, std::ostream& out) {
                                    benchRender(o, *charts, out);
                                  };
                                });
}  // namespace

}  // namespace ps::bench
