// `bench export`'s TIN rows: our TIN mesher (src/tin) on the same heightmaps as the bintree
// rows, against Delatin (npm `delatin`: the same greedy Delaunay insertion, in JavaScript, run
// with node) in the same run. Every mesh's error, ours and Delatin's, is measured here on every
// sample by the same independent locator (tin::measureTinError, vertical distance).
//
// JSON lines (bench "export"):
//   tool planetsculpt-tin: mode fewest | quality, requested_error_m, true_error_m, triangles,
//     vertices, ms (median of repeats), smallest_angle_deg (quality: min_angle_deg, angle_met)
//   tool delatin: requested_error_m, true_error_m, triangles, vertices, ms (median, from scratch)
//   tool compare-tin: per request, triangles_ratio and time_ratio (ours / Delatin's), both
//     true errors
//   tool planet-tin: a planet (Mars from the shared MOLA grid, and a synthetic one) meshed whole
//     with the 3D error, welded: triangles, measured error, Euler characteristic, against the
//     bintree export (terrain::meshToError) at the same error
//   tool overlay: a road stitched (crossing vertices, the added vertices' distance from the
//     terrain mesh) and stenciled (removed and refilled vertices, the footprint's error, the
//     ground's error ratio) into the 20 m TIN, with a picture of both
//   tool control-map: paper 001's experiment: a control region (a disc over a sixth of the tile)
//     at MinError, elsewhere MaxError, for (5, 50) and (10, 100): triangles against MinError
//     everywhere, the reduction, and the measured error inside and outside the region
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>

#include "app/build_paths.hpp"
#include "bench/bench.hpp"
#include "bench/bench_export.hpp"
#include "bench/bench_util.hpp"
#include "bench/tin_pictures.hpp"
#include "core/latlong_chart.hpp"
#include "io/heightmap_import.hpp"
#include "terrain/error_mesher.hpp"
#include "tin/overlay.hpp"
#include "tin/strip.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::bench {

namespace {

namespace fs = std::filesystem;

tin::SampleField fieldOf(const Heightmap& h, double tolerance) {
  tin::SampleField f;
  f.width = f.height = h.side;
  f.heights = h.heights;
  f.metric = tin::ErrorMetric::kVertical;
  f.dx = h.dx;
  f.dy = h.dy;
  f.uniformTolerance = tolerance;
  return f;
}

struct Run {
  double request = 0, trueError = 0, ms = 0;
  std::size_t triangles = 0, vertices = 0;
};

// Delatin's meshes for each request: "" and a reason on stderr when node or the module is absent.
std::vector<Run> runDelatin(const Heightmap& h, const std::vector<double>& requests, int repeats,
                            const fs::path& work) {
  if (!peerMesherReady("delatin")) return {};
  const fs::path script = ps::app::sourceDir() / "scripts" / "martini" / "delatin.mjs";
  const fs::path result = work / (h.name + ".delatin.jsonl");
  std::string csv;
  for (const double e : requests) csv += (csv.empty() ? "" : ",") + std::to_string(e);
  const std::string cmd = "node '" + script.string() + "' '" + writeHeightsF32(h, work).string() +
                          "' " + std::to_string(h.side) + " " + std::to_string(h.side) + " " + csv +
                          " '" + result.string() + "' " + std::to_string(repeats);
  if (std::system(cmd.c_str()) != 0) {
    std::cerr << "bench export: node " << script.string() << " failed; Delatin is skipped\n";
    return {};
  }
  std::vector<Run> runs;
  std::ifstream f(result);
  std::string line;
  while (std::getline(f, line)) {
    const nlohmann::json j = nlohmann::json::parse(line);
    const auto coords = j["coords"].get<std::vector<double>>();
    const auto tris = j["triangles"].get<std::vector<std::uint32_t>>();
    tin::Tin t;
    for (std::size_t i = 0; i + 1 < coords.size(); i += 2) {
      t.xy.emplace_back(coords[i], coords[i + 1]);
      t.h.push_back(
          h.heights[std::size_t(coords[i + 1]) * std::size_t(h.side) + std::size_t(coords[i])]);
    }
    for (std::size_t k = 0; k + 2 < tris.size(); k += 3)
      t.triangles.push_back({tris[k], tris[k + 1], tris[k + 2]});
    const double e = j["max_error"].get<double>();
    const tin::TinErrorCheck check = tin::measureTinError(fieldOf(h, e), t);
    runs.push_back({e, check.maxError, median(j["ms"].get<std::vector<double>>()),
                    t.triangles.size(), t.xy.size()});
  }
  return runs;
}

// Paper 001's experiment on this heightmap: a disc of a sixth of the tile's area as the control
// region.
void controlMapRows(const Heightmap& h, const std::string& outDir, std::ostream& out) {
  const double c = 0.5 * (h.side - 1), r = h.side * std::sqrt(1.0 / (6.0 * M_PI));
  std::vector<bool> inside(h.heights.size());
  std::size_t insideCount = 0;
  for (int j = 0; j < h.side; ++j)
    for (int i = 0; i < h.side; ++i) {
      const bool in = (i - c) * (i - c) + (j - c) * (j - c) <= r * r;
      inside[std::size_t(j) * std::size_t(h.side) + std::size_t(i)] = in;
      insideCount += in;
    }
  for (const auto& [minError, maxError] : {std::pair{5.0, 50.0}, std::pair{10.0, 100.0}}) {
    std::vector<float> tolerance(h.heights.size());
    for (std::size_t k = 0; k < tolerance.size(); ++k)
      tolerance[k] = float(inside[k] ? minError : maxError);
    tin::SampleField field = fieldOf(h, maxError);
    field.perSampleTolerance = tolerance;
    const tin::Tin controlled = tin::buildTin(field, {});
    const tin::Tin everywhere = tin::buildTin(fieldOf(h, minError), {});
    if (!outDir.empty() && minError == 10.0)
      writeControlMapPicture(h, inside, controlled, outDir + "/tin_control_map_" + h.name + ".png");
    // The measured error inside and outside the region, sample by sample.
    std::vector<float> inOnly(tolerance.size()), outOnly(tolerance.size());
    for (std::size_t k = 0; k < tolerance.size(); ++k) {
      inOnly[k] = inside[k] ? 1.0f : 1e30f;  // ratio = error in metres inside, ~0 outside
      outOnly[k] = inside[k] ? 1e30f : 1.0f;
    }
    tin::SampleField probe = fieldOf(h, 1.0);
    probe.perSampleTolerance = inOnly;
    const double errorInside = tin::measureTinError(probe, controlled).maxRatio;
    probe.perSampleTolerance = outOnly;
    const double errorOutside = tin::measureTinError(probe, controlled).maxRatio;
    out << nlohmann::json{{"bench", "export"},
                          {"tool", "control-map"},
                          {"heightmap", h.name},
                          {"min_error_m", minError},
                          {"max_error_m", maxError},
                          {"control_fraction", double(insideCount) / double(h.heights.size())},
                          {"triangles", controlled.triangles.size()},
                          {"triangles_min_error_everywhere", everywhere.triangles.size()},
                          {"reduction", 1.0 - double(controlled.triangles.size()) /
                                                  double(everywhere.triangles.size())},
                          {"measured_error_inside_m", errorInside},
                          {"measured_error_outside_m", errorOutside}}
               .dump()
        << std::endl;
  }
}

// Paper 001's overlay on this heightmap: a 12-sample-wide road along a curve across the tile,
// stitched into the 20 m TIN, and the same road raised 3 m stenciled into it.
void overlayRows(const Heightmap& h, const std::string& outDir, std::ostream& out) {
  const tin::SampleField field = fieldOf(h, 20.0);
  const tin::Tin terrain = tin::buildTin(field, {});
  std::vector<Eigen::Vector2d> centre;
  for (int k = 0; k <= 40; ++k) {
    const double x = 0.1 * h.side + 0.8 * h.side * k / 40.0;
    centre.emplace_back(x, 0.45 * h.side + 0.08 * h.side * std::sin(6.0 * x / h.side));
  }
  const tin::Strip strip = tin::stripAlong(centre, 12.0);
  tin::Road road{strip.xy, {}, strip.triangles};
  for (const auto& p : strip.xy) road.h.push_back(field.heightAt(p.x(), p.y()) + 3.0);
  tin::OverlayResult result[2];
  for (const tin::OverlayMode mode : {tin::OverlayMode::kStitch, tin::OverlayMode::kStencil}) {
    const bool stitch = mode == tin::OverlayMode::kStitch;
    tin::OverlayResult& r = result[stitch ? 0 : 1];
    const double ms = timeMs([&] { r = tin::overlayRoad(field, terrain, road, mode); });
    const tin::MeshTopology top = tin::meshTopology(r.tin.xy.size(), r.tin.triangles);
    nlohmann::json line = {{"bench", "export"},
                           {"tool", "overlay"},
                           {"heightmap", h.name},
                           {"mode", stitch ? "stitch" : "stencil"},
                           {"error_m", 20.0},
                           {"terrain_triangles", terrain.triangles.size()},
                           {"road_triangles", road.triangles.size()},
                           {"triangles", r.tin.triangles.size()},
                           {"euler", top.euler()},
                           {"non_manifold_edges", top.nonManifoldEdges},
                           {"ms", ms}};
    if (stitch) {
      line["crossing_vertices"] = r.report.crossingVertices;
      line["added_vertex_error_m"] = r.report.addedVertexErrorM;
    } else {
      line["removed_terrain_vertices"] = r.report.removedTerrainVertices;
      line["refill_vertices"] = r.report.refillVertices;
      line["footprint_error_m"] = r.report.footprintErrorM;
      line["outside_error_ratio"] = r.report.outsideErrorRatio;
    }
    out << line.dump() << std::endl;
  }
  if (!outDir.empty())
    writeOverlayPicture(h, result[0], result[1], outDir + "/tin_overlay_" + h.name + ".png");
}

}  // namespace

void benchExportTin(const Heightmap& h, const std::vector<double>& requests, int repeats,
                    const fs::path& work, const std::string& outDir, std::ostream& out) {
  const std::string grid = std::to_string(h.side) + "x" + std::to_string(h.side);
  std::vector<Run> ours;
  for (const double e : requests) {
    for (const double angle : {0.0, 20.0, 30.0}) {
      if (angle > 0 && e < 5.0) continue;  // at 1-2 m the greedy TIN holds most samples already
      const tin::SampleField field = fieldOf(h, e);
      tin::Tin t;
      tin::TinReport rep;
      // The fewest-triangles rows race Delatin (medians of repeats); the quality rows are timed
      // once (nothing to race).
      std::vector<double> ms;
      for (int r = 0; r < (angle > 0 ? 1 : repeats); ++r)
        ms.push_back(timeMs([&] { t = tin::buildTin(field, {.minAngleDeg = angle}, &rep); }));
      const tin::TinErrorCheck check = tin::measureTinError(field, t);
      nlohmann::json line = {{"bench", "export"},
                             {"tool", "planetsculpt-tin"},
                             {"heightmap", h.name},
                             {"grid", grid},
                             {"mode", angle > 0 ? "quality" : "fewest"},
                             {"requested_error_m", e},
                             {"true_error_m", check.maxError},
                             {"triangles", t.triangles.size()},
                             {"vertices", t.xy.size()},
                             {"ms", median(ms)},
                             {"smallest_angle_deg", rep.smallestAngleDeg}};
      if (angle > 0) {
        line["min_angle_deg"] = angle;
        line["angle_met"] = rep.angleMet;
        line["steiner_vertices"] = rep.steinerVertices;
      } else {
        ours.push_back({e, check.maxError, median(ms), t.triangles.size(), t.xy.size()});
      }
      out << line.dump() << std::endl;
    }
  }
  const std::vector<Run> theirs = runDelatin(h, requests, repeats, work);
  if (theirs.empty()) {
    writeSkippedPeerRow("delatin", h, out);
  }
  for (const Run& d : theirs) {
    out << nlohmann::json{{"bench", "export"},
                          {"tool", "delatin"},
                          {"heightmap", h.name},
                          {"grid", grid},
                          {"requested_error_m", d.request},
                          {"true_error_m", d.trueError},
                          {"triangles", d.triangles},
                          {"vertices", d.vertices},
                          {"ms", d.ms}}
               .dump()
        << std::endl;
    for (const Run& o : ours) {
      if (o.request != d.request) continue;
      out << nlohmann::json{{"bench", "export"},
                            {"tool", "compare-tin"},
                            {"heightmap", h.name},
                            {"grid", grid},
                            {"requested_error_m", o.request},
                            {"planetsculpt_true_error_m", o.trueError},
                            {"delatin_true_error_m", d.trueError},
                            {"planetsculpt_triangles", o.triangles},
                            {"delatin_triangles", d.triangles},
                            {"triangles_ratio", double(o.triangles) / double(d.triangles)},
                            {"planetsculpt_ms", o.ms},
                            {"delatin_ms", d.ms},
                            {"time_ratio", o.ms / d.ms}}
                 .dump()
          << std::endl;
    }
  }
  controlMapRows(h, outDir, out);
  overlayRows(h, outDir, out);
}

void benchExportPlanetTin(bool quick, std::ostream& out) {
  struct Planet {
    std::string name;
    std::unique_ptr<terrain::Terrain> terrain;
  };
  std::vector<Planet> planets;
  const int side = quick ? 257 : 1025;
  const fs::path mars = ps::app::sharedDir() / "data" / "dem" / "mars_mola_1440x720_u16.png";
  if (fs::exists(mars)) {
    io::ImportOptions o;
    o.radius = 3389500.0;
    o.offset = -32768.0;
    o.westLongitudeDeg = 0.0;
    o.gridSide = side;
    io::ImportResult r = io::importHeightmap(mars, o);
    planets.push_back({"mars-mola", std::make_unique<terrain::Terrain>(
                                        r.planet.chart, std::move(r.planet.heights))});
  } else {
    std::cerr << "bench export: " << mars.string() << " is absent; Mars is skipped\n";
  }
  {
    auto chart = std::make_shared<core::LatLongChart>(core::GridSize::fromSide(side), 1.0e6);
    std::vector<float> h(chart->grid().count());
    // Ridged relief from the direction (seam twins and poles consistent), 0..8 km.
    for (int v = 0; v < side; ++v)
      for (int u = 0; u < side; ++u) {
        const Eigen::Vector3d d = chart->direction(u, v);
        h[chart->grid().index(u, v)] =
            float(4000.0 * (1.0 - std::abs(std::sin(5.1 * d.x() + 2.3 * d.y() * d.z()))) +
                  2000.0 * std::cos(3.7 * d.y() - 1.1) * std::sin(4.3 * d.z() + 0.7) + 2000.0);
      }
    planets.push_back(
        {"synthetic-planet", std::make_unique<terrain::Terrain>(chart, std::move(h))});
  }
  for (const Planet& p : planets) {
    const terrain::Terrain& t = *p.terrain;
    tin::SampleField field;
    field.width = field.height = side;
    field.heights = t.heights();
    field.metric = tin::ErrorMetric::kChart3d;
    field.chart = &t.chart();
    for (const double e : {50.0, 200.0, 1000.0}) {
      field.uniformTolerance = e;
      tin::Tin tn;
      const double ms = timeMs([&] { tn = tin::buildTin(field, {}); });
      const tin::TinErrorCheck check = tin::measureTinError(field, tn);
      const tin::WeldedMesh welded = tin::weldTin(field, tn);
      const tin::MeshTopology top = tin::meshTopology(welded.vertices, welded.triangles);
      terrain::Mesh bintree;
      const double bintreeMs = timeMs([&] { bintree = terrain::meshToError(t, e); });
      out << nlohmann::json{{"bench", "export"},
                            {"tool", "planet-tin"},
                            {"planet", p.name},
                            {"grid", t.grid().label()},
                            {"requested_error_m", e},
                            {"true_error_m", check.maxError},
                            {"triangles", welded.triangles.size()},
                            {"vertices", welded.vertices},
                            {"ms", ms},
                            {"euler", top.euler()},
                            {"border_edges", top.borderEdges},
                            {"bintree_triangles", bintree.triangleCount()},
                            {"bintree_ms", bintreeMs},
                            {"triangles_ratio_to_bintree",
                             double(welded.triangles.size()) / double(bintree.triangleCount())}}
                 .dump()
          << std::endl;
    }
  }
}

}  // namespace ps::bench
