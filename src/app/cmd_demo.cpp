// `planetsculpt demo`: the README's first command. Until video replay lands it is the most the
// project does end to end: default planet -> scripted strokes -> heightmap + view mesh + pictures.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>

#include "app/command_registry.hpp"
#include "app/commands.hpp"
#include "app/default_planet.hpp"
#include "app/progress.hpp"
#include "app/snapshot.hpp"
#include "core/grid.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/stroke_script.hpp"
#include "io/heightmap_export.hpp"
#include "io/mesh_export.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"

namespace ps::app {

namespace {

// Oblique view of the highest range on the planet, from 350 km up and 900 km away: close enough
// that relief shows, far enough to see the tessellation adapt with distance.
terrain::Camera defaultView(const terrain::Terrain& t) {
  const auto h = t.heights();
  const auto peak = std::size_t(std::max_element(h.begin(), h.end()) - h.begin());
  const int side = t.grid().side();
  const int pu = int(peak % std::size_t(side)), pv = int(peak / std::size_t(side));
  const Eigen::Vector3d up = t.chart().up(pu, pv);
  Eigen::Vector3d east = Eigen::Vector3d::UnitZ().cross(up);
  if (east.norm() < 1e-6) east = Eigen::Vector3d::UnitX();
  east.normalize();
  const Eigen::Vector3d north = up.cross(east);
  const double R = t.chart().radius();
  const Eigen::Vector3d target = R * up;
  const Eigen::Vector3d eye = (R + 3.5e5) * up - 9e5 * (0.8 * north + 0.6 * east).normalized();
  return terrain::Camera::lookAt(eye, target, eye.normalized(), 1280, 720,
                                 60 * std::numbers::pi / 180);
}

void writePng(const cv::Mat& img, const std::filesystem::path& path) {
  if (!cv::imwrite(path.string(), img)) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

int runDemo(const DemoOptions& o) {
  std::filesystem::create_directories(o.outDir);
  const std::filesystem::path out(o.outDir);
  auto planet = makeDefaultPlanet(o.gridLevel, o.seed);
  nlohmann::json summary = {{"grid", planet->grid().label()},
                            {"radius_m", planet->chart().radius()},
                            {"seed", o.seed},
                            {"error_rule", terrain::toString(planet->bounds().rule())}};

  {
    // The bundled stroke script sculpts the planet through the edit pipeline.
    std::filesystem::path script = o.strokes;
    if (script.empty()) {
      script = "data/demo-strokes.txt";
      if (!std::filesystem::exists(script))
        script = std::filesystem::path(PS_SOURCE_DIR) / "data/demo-strokes.txt";
    }
    Progress p("sculpt " + script.filename().string());
    const edit::StrokeScript strokes = edit::loadStrokeScript(script);
    edit::EditPipeline pipeline(*planet);
    const auto report = edit::runStrokeScript(strokes, pipeline);
    p.done(std::to_string(report.strokes) + " strokes, " + std::to_string(report.edits.stamps) +
           " stamps, " + std::to_string(report.edits.modifiedVertices) + " vertex changes");
    summary["sculpt"] = {{"script", script.string()},
                         {"strokes", report.strokes},
                         {"stamps", report.edits.stamps},
                         {"modified_vertices", report.edits.modifiedVertices},
                         {"edit_ms", report.edits.totalMs}};
  }

  {
    Progress p("heightmap");
    const int h = std::min(planet->grid().m(), 4096), w = 2 * h;
    const auto raster = io::resampleEquirectangular(*planet, w, h);
    p.update(0.4);
    io::writeHeightPng16(raster, out / "heightmap.png");
    p.update(0.7);
    const auto preview = io::resampleEquirectangular(*planet, 1024, 512);
    io::writeReliefPreview(preview, std::numbers::pi * planet->chart().radius() / 512,
                           out / "relief.png");
    p.done((out / "heightmap.png").string() + " " + std::to_string(w) + "x" + std::to_string(h));
    summary["heightmap"] = {{"file", "heightmap.png"}, {"width", w}, {"height", h}};
  }

  {
    Progress p("tessellate");
    const terrain::Camera cam = defaultView(*planet);
    terrain::Tessellator tess;
    terrain::TessellationSettings s;
    s.distMaxPx = o.distMaxPx;
    s.triangleBudget = o.triangleBudget;
    const auto& mesh = tess.tessellate(*planet, cam, s);
    p.update(0.3);
    const auto err = terrain::measureScreenError(*planet, cam, mesh);
    p.update(0.5);
    io::writeObj(*planet, mesh, out / "view.obj");
    p.update(0.8);
    writePng(renderSnapshot(*planet, mesh, cam, false), out / "view.png");
    writePng(renderSnapshot(*planet, mesh, cam, true), out / "view_wireframe.png");
    p.done(std::to_string(mesh.triangleCount()) + " triangles, measured screen error " +
           std::to_string(err.maxPx) + " px <= " + std::to_string(tess.stats().effectiveDistMaxPx));
    summary["view"] = {{"triangles", mesh.triangleCount()},
                       {"dist_max_px", s.distMaxPx},
                       {"effective_dist_max_px", tess.stats().effectiveDistMaxPx},
                       {"measured_max_screen_error_px", err.maxPx},
                       {"files", {"view.obj", "view.png", "view_wireframe.png"}}};
  }
  std::ofstream(out / "summary.json") << summary.dump(2) << "\n";
  std::cout << "wrote " << (out / "heightmap.png").string()
            << ", relief.png, view.obj, view.png, view_wireframe.png, summary.json\n";
  return 0;
}

namespace {
const CommandRegistration kDemo([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto o = std::make_shared<DemoOptions>();
  auto side = std::make_shared<long long>(4097);
  sub = root.add_subcommand("demo",
                            "Main job on the bundled default: generate, sculpt, export, pictures");
  sub->add_option("--out", o->outDir, "Output folder")->capture_default_str();
  sub->add_option("--grid", *side, "Grid side, 2^n+1 (e.g. 2049, 4097, 8193)")
      ->capture_default_str();
  sub->add_option("--seed", o->seed, "Relief seed")->capture_default_str();
  sub->add_option("--strokes", o->strokes, "Stroke script (default: data/demo-strokes.txt)");
  sub->add_option("--dist-max", o->distMaxPx, "Screen-space error bound in pixels")
      ->capture_default_str();
  sub->add_option("--budget", o->triangleBudget, "Triangle budget (0: none)")
      ->capture_default_str();
  return [o, side] {
    o->gridLevel = core::GridSize::fromSide(*side).n();
    return runDemo(*o);
  };
});
}  // namespace

}  // namespace ps::app
