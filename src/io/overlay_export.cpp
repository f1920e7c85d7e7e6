#include "io/overlay_export.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"
#include "io/height_image.hpp"
#include "io/mesh_export.hpp"
#include "io/mesh_writers.hpp"
#include "io/planet_file.hpp"
#include "io/road_placement.hpp"
#include "io/road_poles.hpp"
#include "io/tin_export.hpp"
#include "tin/plane_stitch.hpp"
#include "tin/road_checks.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_locator.hpp"

namespace ps::io {

namespace {

using core::exactNumber;
constexpr double kDeg = std::numbers::pi / 180.0;

// A flat terrain mesh (what `export --tin` writes for a heightmap: x east, y north, z up, in
// metres): the TIN itself in lattice coordinates, and its surface sampled on a lattice of
// `spacing` metres (default: the smallest gap between its vertices' distinct x and y values,
// which is the heightmap's spacing for this project's exports), for the stencil's re-meshing.
struct MeshTerrain {
  HeightSamples samples;
  tin::Tin tin;
};

double smallestGap(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  double gap = INFINITY;
  for (std::size_t k = 1; k < values.size(); ++k)
    if (values[k] > values[k - 1]) gap = std::min(gap, values[k] - values[k - 1]);
  return gap;
}

MeshTerrain meshTerrain(const ObjTriangles& mesh, std::optional<double> spacing,
                        const std::string& name) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  std::vector<double> xs, ys;
  for (const auto& p : mesh.vertices) {
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    xs.push_back(p.x()), ys.push_back(p.y());
  }
  // A heightfield over its bounding rectangle: the triangles' areas seen from above add up to
  // the rectangle's, with no fold (a planet's mesh, or a surface with overhangs, would not).
  double covered = 0;
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]],
                          &c = mesh.vertices[tri[2]];
    covered += 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }
  const double rectangle = (hi.x() - lo.x()) * (hi.y() - lo.y());
  if (!(rectangle > 0) || std::abs(covered - rectangle) > 1e-6 * rectangle)
    throw core::InputError(name +
                           ": the terrain mesh is not a heightfield over its bounding "
                           "rectangle (its triangles cover " +
                           exactNumber(covered / rectangle) +
                           " times the rectangle seen from above); give a planet file or a "
                           "heightmap, or a flat mesh as `export --tin` writes");
  const double dx = spacing ? *spacing : smallestGap(xs), dy = spacing ? *spacing : smallestGap(ys);
  if (!(std::isfinite(dx) && dx > 0 && std::isfinite(dy) && dy > 0))
    throw core::InputError(name + ": the terrain mesh has no extent in x or y");
  const double w = std::round((hi.x() - lo.x()) / dx) + 1,
               h = std::round((hi.y() - lo.y()) / dy) + 1;
  if (w * h > double(std::uint64_t(1) << 26))
    throw core::InputError(name + ": sampling the terrain mesh every " + exactNumber(dx) + " x " +
                           exactNumber(dy) + " m takes " + exactNumber(w * h) +
                           " samples; give a coarser --spacing");
  MeshTerrain t;
  HeightSamples& s = t.samples;
  s.width = int(w), s.height = int(h), s.dx = dx, s.dy = dy;
  for (const auto& p : mesh.vertices) {
    t.tin.xy.emplace_back((p.x() - lo.x()) / dx, (p.y() - lo.y()) / dy);
    t.tin.h.push_back(p.z());
  }
  for (auto tri : mesh.triangles) {  // counter-clockwise seen from above
    const Eigen::Vector2d &a = t.tin.xy[tri[0]], &b = t.tin.xy[tri[1]], &c = t.tin.xy[tri[2]];
    if ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x() < 0) std::swap(tri[1], tri[2]);
    t.tin.triangles.push_back(tri);
  }
  const tin::TinLocator where(t.tin.xy, t.tin.triangles, w, h);
  s.heights.resize(std::size_t(w) * std::size_t(h));
  for (int j = 0; j < s.height; ++j)
    for (int i = 0; i < s.width; ++i) {
      double z = NAN;
      where.visit(
          {i, j},
          [&](const tin::TinLocator::Hit& hit) {
            if (std::isnan(z)) {
              const auto& tri = t.tin.triangles[hit.triangle];
              z = hit.l0 * t.tin.h[tri[0]] + hit.l1 * t.tin.h[tri[1]] + hit.l2 * t.tin.h[tri[2]];
            }
          },
          1e-7);
      if (std::isnan(z))
        throw core::InputError(name + ": the terrain mesh leaves a hole at (" +
                               exactNumber(lo.x() + i * dx) + ", " + exactNumber(lo.y() + j * dy) +
                               ") m");
      s.heights[std::size_t(j) * std::size_t(s.width) + std::size_t(i)] = float(z);
    }
  s.notes.push_back("a terrain mesh of " + std::to_string(mesh.vertices.size()) +
                    " vertices, sampled every " + exactNumber(dx) + " x " + exactNumber(dy) +
                    " m (" + std::to_string(s.width) + "x" + std::to_string(s.height) +
                    " samples) for the stencil's re-meshing; x, y "
                    "measured from its south-west corner (" +
                    exactNumber(lo.x()) + ", " + exactNumber(lo.y()) + ") m");
  return t;
}

// What an overlay made: the mesh (positions, groups), its triangles for the topology check, and
// the summary's keys that depend on how it was made.
struct OverlayMesh {
  MeshData mesh;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  nlohmann::json summary;
};

OverlayMesh toOverlayMesh(std::vector<Eigen::Vector3d> positions,
                          std::vector<std::array<std::uint32_t, 3>> triangles,
                          const std::vector<std::uint8_t>& group, tin::OverlayMode mode) {
  OverlayMesh made;
  made.mesh.positions = std::move(positions);
  for (const auto& t : triangles)
    made.mesh.indices.insert(made.mesh.indices.end(), t.begin(), t.end());
  made.mesh.triangleGroup = group;
  made.mesh.groupNames = {"terrain", "road"};
  made.mesh.description =
      "PlanetSculpt TIN with a road " +
      std::string(mode == tin::OverlayMode::kStitch ? "stitched" : "stenciled") +
      " in: " + std::to_string(made.mesh.positions.size()) + " vertices, " +
      std::to_string(triangles.size()) + " triangles, metres";
  made.triangles = std::move(triangles);
  return made;
}

// The road laid in the terrain's grid (tin/overlay.hpp), then welded where the chart makes
// lattice points one.
OverlayMesh overlayInGrid(const tin::SampleField& field, const tin::Tin& terrainTin,
                          const LaidRoad& laid, tin::OverlayMode mode, const std::string& name) {
  tin::OverlayResult r;
  try {
    r = tin::overlayRoad(field, terrainTin, laid.road, mode);
  } catch (const core::InputError& e) {
    throw core::InputError(name + ": " + e.what());
  }
  const tin::WeldedMesh welded = tin::weldTin(field, r.tin);
  std::vector<Eigen::Vector3d> positions(welded.vertices, Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < r.tin.xy.size(); ++v) positions[welded.vertexOf[v]] = r.positions[v];
  std::vector<std::uint8_t> group;
  for (std::size_t k = 0; k < welded.triangles.size(); ++k)
    group.push_back(r.onRoad[welded.sourceTriangle[k]]);
  OverlayMesh made = toOverlayMesh(std::move(positions), welded.triangles, group, mode);
  const tin::OverlayReport& rep = r.report;
  // in the grid: cut along a planet's glued sides, edges halved where the chart bends them, a
  // copy beyond each glued side it crosses
  made.summary = {{"road_triangles_laid", rep.roadTriangles},
                  {"road_pieces", laid.pieces},
                  {"road_stray_m", laid.strayM},
                  {"road_halved_edges", laid.halvedEdges},
                  {"road_triangles_clipped", rep.clippedRoadTriangles}};
  if (mode == tin::OverlayMode::kStitch) {
    made.summary["stitched_in"] = "grid";
    made.summary["crossing_vertices"] = rep.crossingVertices;
    made.summary["added_vertex_error_m"] = rep.addedVertexErrorM;
    if (field.metric == tin::ErrorMetric::kChart3d) {
      made.summary["road_draped_edges"] = rep.drapedEdges;
      made.summary["road_undraped_edges"] = rep.undrapedEdges;
      made.summary["road_drape_move_m"] = rep.drapeMoveM;
    }
  } else {
    made.summary["removed_terrain_vertices"] = rep.removedTerrainVertices;
    made.summary["refill_vertices"] = rep.refillVertices;
    made.summary["footprint_error_m"] = rep.footprintErrorM;
    made.summary["outside_error_ratio"] = rep.outsideErrorRatio;
  }
  return made;
}

// The road stitched into the planet's welded terrain mesh in its own plane (tin/plane_stitch.hpp):
// its vertices and edges exactly where the plane's rays through them meet the mesh.
OverlayMesh stitchInRoadPlane(const tin::SampleField& field, const tin::Tin& terrainTin,
                              const ObjTriangles& roadObj, const RoadFrame& frame,
                              const std::string& name) {
  const tin::WeldedMesh welded = tin::weldTin(field, terrainTin);
  tin::SurfaceMesh surface;
  surface.positions.assign(welded.vertices, Eigen::Vector3d::Zero());
  for (std::size_t v = terrainTin.xy.size(); v-- > 0;)  // the first of a welded vertex's sources
    surface.positions[welded.vertexOf[v]] =
        field.positionAt(terrainTin.xy[v].x(), terrainTin.xy[v].y(), terrainTin.h[v]);
  surface.triangles = welded.triangles;
  const tin::RoadPlane plane{Eigen::Vector3d::Zero(), frame.origin, frame.up, frame.x, frame.y};
  std::vector<Eigen::Vector2d> xy;
  for (const Eigen::Vector3d& p : roadObj.vertices) xy.emplace_back(p.x(), p.y());
  tin::PlaneStitch stitched;
  try {
    stitched = tin::stitchInPlane(surface, plane, xy, roadObj.triangles);
  } catch (const tin::SurfaceUnseenInPlane&) {
    throw;  // the caller's to stitch in the grid instead
  } catch (const core::InputError& e) {
    throw core::InputError(name + ": " + e.what());
  }
  OverlayMesh made = toOverlayMesh(std::move(stitched.mesh.positions), stitched.mesh.triangles,
                                   stitched.onRoad, tin::OverlayMode::kStitch);
  // Its edges run exactly along the planes through the centre: nothing strays, nothing halved.
  made.summary = {{"stitched_in", "road plane"},
                  {"road_triangles_laid", roadObj.triangles.size()},
                  {"road_pieces", 1},
                  {"road_stray_m", 0.0},
                  {"road_halved_edges", 0},
                  {"road_triangles_clipped", 0},
                  {"remeshed_terrain_triangles", stitched.regionTriangles},
                  {"crossing_vertices", stitched.crossingVertices},
                  {"added_vertex_error_m", stitched.addedVertexErrorM},
                  {"road_draped_edges", tin::edgesOf(roadObj.triangles).size()},
                  {"road_undraped_edges", 0},
                  {"road_drape_move_m", 0.0}};
  return made;
}

void requirePlace(const OverlayOptions& o, const std::string& name) {
  if (!o.at)
    throw core::InputError(name +
                           ": on a planet the road needs --at (LAT,LON[,HEADING] on a "
                           "sphere; AROUND,ACROSS on a torus; AROUND,ALONG on a cylinder)");
}

// Whether the road's footprint in its plane holds one of lat-long's poles.
bool holdsLatLongPole(const core::Chart& chart, double m, const RoadFrame& frame,
                      const ObjTriangles& road) {
  for (const auto& pole : polesInPlane(chart, m, frame)) {
    const Eigen::Vector2d p = pole.first;
    for (const auto& t : road.triangles) {
      const Eigen::Vector2d a = road.vertices[t[0]].head<2>(), b = road.vertices[t[1]].head<2>(),
                            c = road.vertices[t[2]].head<2>();
      const double whole = tin::signedArea(a, b, c);
      if (whole != 0 && tin::signedArea(p, b, c) / whole >= -1e-12 &&
          tin::signedArea(a, p, c) / whole >= -1e-12 && tin::signedArea(a, b, p) / whole >= -1e-12)
        return true;
    }
  }
  return false;
}

struct Overlaid {
  OverlayMesh made;
  bool holdsPole = false;
};

// On a sphere a stitched road goes in its own plane (tin/plane_stitch.hpp): exact, and blind to
// the chart's grid, whose pole rows and folds it never meets. Where the surface about it is not
// seen one to one from the centre (a TIN triangle with three corners on one great circle, as at
// the end of an octahedral fold), where options ask for it, and for a stencil, a flat terrain or
// a tube, it is laid in the grid (tin/overlay.hpp).
Overlaid overlayRoadOnto(const tin::SampleField& field, const tin::Tin& terrainTin,
                         const ObjTriangles& roadObj, const OverlayOptions& o,
                         const std::string& name, std::vector<std::string>& notes) {
  const bool sphere = field.metric == tin::ErrorMetric::kChart3d && field.wholeChart() &&
                      field.chart->sphereRadius() > 0;
  const bool stitch = o.mode == tin::OverlayMode::kStitch;
  if (stitch && sphere && !o.stitchInGrid) {
    requirePlace(o, name);
    const RoadFrame frame = roadFrame(*field.chart, *o.at, name);
    const bool holds = holdsLatLongPole(*field.chart, field.width - 1, frame, roadObj);
    try {
      return {stitchInRoadPlane(field, terrainTin, roadObj, frame, name), holds};
    } catch (const tin::SurfaceUnseenInPlane& e) {
      // In the grid, a road over lat-long's pole folds the surface (its row is one point).
      if (holds) throw core::InputError(name + ": " + e.what());
      notes.push_back(name + ": stitched in the " + field.chart->name() +
                      " chart's grid, not in the road's plane: " + e.what());
    }
  }
  const LaidRoad laid = placeRoad(roadObj, field, o, name);
  if (laid.holdsPole && stitch)
    throw core::InputError(name +
                           ": the road holds a pole of the lat-long chart, where a grid row is one "
                           "point: stitched in the grid, its edges and the terrain's would cross "
                           "there in points the surface cannot tell apart; stitch it in its own "
                           "plane (the default) or lay it with --mode stencil");
  return {overlayInGrid(field, terrainTin, laid, o.mode, name), laid.holdsPole};
}

}  // namespace

LaidRoad placeRoad(const ObjTriangles& obj, const tin::SampleField& field, const OverlayOptions& o,
                   const std::string& name) {
  LaidRoad laid;
  if (field.metric == tin::ErrorMetric::kVertical) {
    const std::array<double, 3> at = o.at.value_or(std::array<double, 3>{0, 0, 0});
    // The road's +y axis points at azimuth `heading`, its +x axis 90 degrees clockwise from it.
    const double heading = at[2] * kDeg, ch = std::cos(heading), sh = std::sin(heading);
    laid.road.triangles = obj.triangles;
    for (const Eigen::Vector3d& p : obj.vertices) {
      const double east = at[0] + p.x() * ch + p.y() * sh;
      const double north = at[1] - p.x() * sh + p.y() * ch;
      laid.road.xy.emplace_back(east / field.dx, north / field.dy);
      laid.road.h.push_back(p.z());
    }
    return laid;
  }
  requirePlace(o, name);
  laid = layRoadOnPlanet(obj, *field.chart, field.width - 1, *o.at, o.errorM, name);
  for (Eigen::Vector2d& p : laid.road.xy) p -= Eigen::Vector2d(field.i0, field.j0);
  return laid;
}

nlohmann::json overlayFromFiles(const std::filesystem::path& terrainPath,
                                const ImportOptions& heightmapOptions,
                                const std::filesystem::path& roadPath,
                                const std::filesystem::path& out, ExportFormat format,
                                const OverlayOptions& o, std::vector<std::string>& notes) {
  if (!isMeshFormat(format))
    throw core::InputError("overlay writes a mesh (obj, ply, glb), not " + toString(format));
  if (!(std::isfinite(o.errorM) && o.errorM > 0))
    throw core::InputError("--error " + core::exactNumber(o.errorM) +
                           " m: the terrain's TIN needs an error above 0");
  const ObjTriangles roadObj = readObjTriangles(roadPath);
  std::unique_ptr<terrain::Terrain> planet;
  HeightSamples samples;
  tin::SampleField field;
  std::optional<tin::Tin> meshTin;  // a terrain given as a mesh is its own TIN
  std::string ext = terrainPath.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".obj") {
    MeshTerrain m =
        meshTerrain(readObjTriangles(terrainPath), heightmapOptions.spacing, terrainPath.string());
    samples = std::move(m.samples);
    meshTin = std::move(m.tin);
    notes = samples.notes;
    field = heightSampleField(samples);
  } else if (isPlanetFile(terrainPath)) {
    planet = loadPlanet(terrainPath);
    field = terrainSampleField(*planet);
  } else {
    samples = heightSamples(readHeightImage(terrainPath, heightmapOptions.encoding),
                            heightmapOptions, terrainPath.string());
    notes = samples.notes;
    field = heightSampleField(samples);
  }
  field.uniformTolerance = o.errorM;
  const tin::Tin terrainTin = meshTin ? *meshTin : tin::buildTin(field, {});
  const bool stitch = o.mode == tin::OverlayMode::kStitch;
  const Overlaid overlaid =
      overlayRoadOnto(field, terrainTin, roadObj, o, roadPath.string(), notes);
  const OverlayMesh& made = overlaid.made;
  const MeshData& mesh = made.mesh;
  const tin::MeshTopology top = tin::meshTopology(mesh.positions.size(), made.triangles);
  std::size_t onRoad = 0;
  for (const std::uint8_t g : mesh.triangleGroup) onRoad += g;
  nlohmann::json summary = {{"file", out.string()},
                            {"format", toString(format)},
                            {"mode", stitch ? "stitch" : "stencil"},
                            {"error_m", o.errorM},
                            {"terrain_tin_vertices", terrainTin.xy.size()},
                            {"road_vertices", roadObj.vertices.size()},
                            {"road_triangles", roadObj.triangles.size()},
                            {"road_holds_pole", overlaid.holdsPole},
                            {"vertices", mesh.positions.size()},
                            {"triangles", made.triangles.size()},
                            {"road_group_triangles", onRoad},
                            {"euler", top.euler()},
                            {"border_edges", top.borderEdges},
                            {"non_manifold_edges", top.nonManifoldEdges}};
  summary.update(made.summary);
  writeMeshFile(mesh, meshFormatOf(format), out,
                nlohmann::json({{"planetsculpt", {{"overlay", summary}}}}).dump());
  return summary;
}

}  // namespace ps::io
