#include "bench/frame_skips.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "bench/bench_util.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/settler.hpp"

namespace ps::bench {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// "with" is the time with the skip, "without" the time of doing the work.
nlohmann::json saving(double withMs, double withoutMs) {
  return {{"with_ms", round3(withMs)},
          {"without_ms", round3(withoutMs)},
          {"saved_ms", round3(withoutMs - withMs)},
          {"ratio", withMs > 0 ? std::round(withoutMs / withMs * 10) / 10 : 0.0}};
}

template <class F>
double medianMs(int repeats, F&& f) {
  std::vector<double> t;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(msSince(t0));
  }
  return median(t);
}

nlohmann::json culling(render::PlanetRenderer& renderer, const terrain::Terrain& planet,
                       const SkipInputs& in) {
  std::vector<double> tessOn, tessOff, drawOn, drawOff, triOn, triOff;
  terrain::Tessellator on, off;
  for (const auto& cam : in.views) {
    auto culled = in.settings, whole = in.settings;
    culled.cull = true;
    whole.cull = false;
    for (int r = 0; r < in.repeats; ++r) {
      on.invalidate();
      off.invalidate();
      auto t0 = std::chrono::steady_clock::now();
      const terrain::Mesh& a = on.tessellate(planet, cam, culled);
      tessOn.push_back(msSince(t0));
      t0 = std::chrono::steady_clock::now();
      const terrain::Mesh& b = off.tessellate(planet, cam, whole);
      tessOff.push_back(msSince(t0));
      t0 = std::chrono::steady_clock::now();
      renderer.renderAR(in.background, planet, a, cam, {});
      drawOn.push_back(msSince(t0));
      t0 = std::chrono::steady_clock::now();
      renderer.renderAR(in.background, planet, b, cam, {});
      drawOff.push_back(msSince(t0));
      triOn.push_back(double(a.triangleCount()));
      triOff.push_back(double(b.triangleCount()));
    }
  }
  // Note: the whole planet's mesh also runs into the triangle budget sooner, which coarsens it.
  return {{"views", in.views.size()},
          {"tessellate", saving(median(tessOn), median(tessOff))},
          {"render_with_upload", saving(median(drawOn), median(drawOff))},
          {"triangles_with", median(triOn)},
          {"triangles_without", median(triOff)}};
}

nlohmann::json reuse(const terrain::Terrain& planet, const SkipInputs& in) {
  const auto& cam = in.views.back();
  terrain::Tessellator kept, fresh;
  kept.tessellate(planet, cam, in.settings);
  const int n = 4 * in.repeats;
  const double withMs = medianMs(n, [&] { kept.tessellate(planet, cam, in.settings); });
  const double withoutMs = medianMs(n, [&] {
    fresh.invalidate();
    fresh.tessellate(planet, cam, in.settings);
  });
  return saving(withMs, withoutMs);
}

// Uploads, three ways on the same views: the mesh unchanged (nothing sent), after a local edit
// under the held view (only its changed chunks sent), and the same edit sent whole.
nlohmann::json uploads(render::PlanetRenderer& renderer, const terrain::Terrain& planet,
                       const SkipInputs& in) {
  const auto& cam = in.views.back();
  terrain::Tessellator tess;
  const terrain::Mesh mesh = tess.tessellate(planet, cam, in.settings);
  renderer.renderAR(in.background, planet, mesh, cam, {});
  const int n = 4 * in.repeats;
  const double unchangedMs =
      medianMs(n, [&] { renderer.renderAR(in.background, planet, mesh, cam, {}); });

  // A 50 km bump where the view looks (the vertex nearest the middle of the mesh).
  terrain::Terrain edited(planet.chartPtr(), {planet.heights().begin(), planet.heights().end()});
  const std::uint64_t middle = mesh.gridIndex[mesh.gridIndex.size() / 2];
  const int side = planet.grid().side();
  edit::EditPipeline pipe(edited);
  pipe.setUndoEnabled(false);
  edit::BrushSettings b;
  b.radius = 50e3;
  b.strength = 2000;
  const core::GridPoint c{int(middle % std::uint64_t(side)), int(middle / std::uint64_t(side))};
  pipe.apply(edit::GaussianBrush(b), {edited.chart().position(c.u, c.v, 0.0), 0.0});
  terrain::Tessellator tessEdited;
  const terrain::Mesh after = tessEdited.tessellate(edited, cam, in.settings);

  std::size_t partialBytes = 0, fullBytes = 0;
  auto alternate = [&](bool partial, std::size_t& bytes) {
    renderer.setPartialUploads(partial);
    std::vector<double> t;
    for (int i = 0; i < n; ++i) {
      renderer.renderAR(in.background, planet, mesh, cam, {});  // back to the old mesh
      const auto t0 = std::chrono::steady_clock::now();
      renderer.renderAR(in.background, edited, after, cam, {});
      t.push_back(msSince(t0));
      bytes = renderer.stats().uploadedBytes;
    }
    return median(t);
  };
  const double partialMs = alternate(true, partialBytes);
  const double fullMs = alternate(false, fullBytes);
  renderer.setPartialUploads(true);
  return {{"unchanged_mesh", saving(unchangedMs, fullMs)},
          {"changed_chunks_after_edit", saving(partialMs, fullMs)},
          {"bytes_sent_after_edit", partialBytes},
          {"bytes_of_mesh", fullBytes},
          {"triangles", after.triangleCount()}};
}

// A crater pressed into a copy of the planet, then one settling step over the cells the crater
// made active, against one step over every cell (what a solver without an active set does).
nlohmann::json erosion(const terrain::Terrain& planet, const SkipInputs& in) {
  terrain::Terrain copy(planet.chartPtr(), {planet.heights().begin(), planet.heights().end()});
  sand::SettleSettings one;
  one.maxStepsPerFrame = 1;
  one.cellBudget = std::numeric_limits<std::size_t>::max();
  sand::Settler settler(copy, sand::Material::sand(), one);
  sand::DisplacementSettings ds;
  ds.radius = 400e3;
  ds.rampartWidth = 0.5;
  sand::DisplacementTool tool(copy.chartPtr(), ds, &settler);
  edit::EditPipeline pipe(copy);
  pipe.setUndoEnabled(false);
  const core::GridPoint c{copy.grid().m() / 3, copy.grid().m() / 2};
  const Eigen::Vector3d up = copy.chart().up(c.u, c.v);
  const double h = double(copy.heights()[copy.grid().index(c.u, c.v)]);
  pipe.apply(tool, {copy.chart().position(c.u, c.v, h) + 0.3 * ds.radius * up, 0.0});
  settler.frame();  // the first frame loads the tiles
  std::vector<double> active, all;
  std::size_t activeCells = 0, allCells = 0;
  for (int r = 0; r < in.repeats; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    const auto a = settler.frame();
    active.push_back(msSince(t0));
    activeCells = a.cellSteps;
  }
  for (int r = 0; r < std::max(2, in.repeats / 2); ++r) {
    settler.settleAll();
    const auto t0 = std::chrono::steady_clock::now();
    const auto b = settler.frame();
    all.push_back(msSince(t0));
    allCells = b.cellSteps;
  }
  auto j = saving(median(active), median(all));
  j["cells_with"] = activeCells;
  j["cells_without"] = allCells;
  return j;
}

}  // namespace

nlohmann::json measureSkips(render::PlanetRenderer& renderer, const terrain::Terrain& planet,
                            const SkipInputs& in) {
  nlohmann::json j;
  if (in.views.empty()) return {{"skipped", "no view of the planet"}};
  j["culling"] = culling(renderer, planet, in);
  j["unchanged_view_reused"] = reuse(planet, in);
  j["upload_only_changed_mesh"] = uploads(renderer, planet, in);
  j["erosion_active_cells"] = erosion(planet, in);
  // The tool that does not touch: the frames whose edit was skipped cost editIdleMs; had they
  // run a stamp like the touching frames, each would have cost editTouchingMs.
  auto idle = saving(in.editIdleMs, in.editTouchingMs);
  idle["frames_skipped"] = in.idleFrames;
  j["no_edit_while_not_touching"] = idle;
  // The overview every Nth frame: per frame, overviewMs / N instead of overviewMs.
  auto ov = saving(in.overviewMs / in.overviewEvery, in.overviewMs);
  ov["every"] = in.overviewEvery;
  j["overview_lower_rate"] = ov;
  return j;
}

}  // namespace ps::bench
