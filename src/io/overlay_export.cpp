#include "io/overlay_export.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"
#include "io/height_image.hpp"
#include "io/mesh_export.hpp"
#include "io/mesh_writers.hpp"
#include "io/planet_file.hpp"
#include "io/tin_export.hpp"
#include "tin/tin_check.hpp"

namespace ps::io {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace

tin::Track placeTrack(const ObjTriangles& obj, const tin::SampleField& field,
                      const OverlayOptions& o, const std::string& name) {
  tin::Track track;
  track.triangles = obj.triangles;
  const std::array<double, 3> at = o.at.value_or(std::array<double, 3>{0, 0, 0});
  const double heading = at[2] * kDeg;
  // The track's +y axis points at azimuth `heading`, its +x axis 90 degrees clockwise from it.
  const double ch = std::cos(heading), sh = std::sin(heading);
  if (field.metric == tin::ErrorMetric::kVertical) {
    for (const Eigen::Vector3d& p : obj.vertices) {
      const double east = at[0] + p.x() * ch + p.y() * sh;
      const double north = at[1] - p.x() * sh + p.y() * ch;
      track.xy.emplace_back(east / field.dx, north / field.dy);
      track.h.push_back(p.z());
    }
    return track;
  }
  if (!o.at) throw core::InputError(name + ": on a planet the track needs --at LAT,LON[,HEADING]");
  if (!(std::abs(at[0]) <= 90 && std::abs(at[1]) <= 180))
    throw core::InputError("--at " + core::exactNumber(at[0]) + "," + core::exactNumber(at[1]) +
                           ": latitude must be within +-90 and longitude within +-180 degrees");
  const double lat = at[0] * kDeg, lon = at[1] * kDeg, r = field.chart->radius();
  const Eigen::Vector3d up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                           std::sin(lat));
  const Eigen::Vector3d east(-std::sin(lon), std::cos(lon), 0);
  const Eigen::Vector3d north = up.cross(east);
  const Eigen::Vector3d xAxis = east * ch - north * sh, yAxis = north * ch + east * sh;
  const double m = field.width - 1;
  double uLo = INFINITY, uHi = -INFINITY;
  for (const Eigen::Vector3d& p : obj.vertices) {
    // Onto the sphere through its centre (the tangent plane's gnomonic projection).
    const Eigen::Vector3d onPlane = r * up + p.x() * xAxis + p.y() * yAxis;
    const auto uv = field.chart->inverse(onPlane);
    if (!uv) throw core::InputError(name + ": a track vertex has no place on the planet");
    if (uv->y() < 1 || uv->y() > m - 1)
      throw core::InputError(name +
                             ": the track reaches a pole's row of the lat-long chart; "
                             "place it away from the poles");
    uLo = std::min(uLo, uv->x()), uHi = std::max(uHi, uv->x());
    track.xy.push_back(*uv - Eigen::Vector2d(field.i0, field.j0));
    track.h.push_back(p.z());
  }
  if (uHi - uLo > 0.5 * m)
    throw core::InputError(name +
                           ": the track crosses the +-180 degree meridian (the chart's "
                           "seam); place it elsewhere");
  return track;
}

nlohmann::json overlayFromFiles(const std::filesystem::path& terrainPath,
                                const ImportOptions& heightmapOptions,
                                const std::filesystem::path& trackPath,
                                const std::filesystem::path& out, ExportFormat format,
                                const OverlayOptions& o, std::vector<std::string>& notes) {
  if (!isMeshFormat(format))
    throw core::InputError("overlay writes a mesh (obj, ply, glb), not " + toString(format));
  if (!(std::isfinite(o.errorM) && o.errorM > 0))
    throw core::InputError("--error " + core::exactNumber(o.errorM) +
                           " m: the terrain's TIN needs an error above 0");
  const ObjTriangles trackObj = readObjTriangles(trackPath);
  std::unique_ptr<terrain::Terrain> planet;
  HeightSamples samples;
  tin::SampleField field;
  if (isPlanetFile(terrainPath)) {
    planet = loadPlanet(terrainPath);
    field = terrainSampleField(*planet);
  } else {
    samples = heightSamples(readHeightImage(terrainPath, heightmapOptions.encoding),
                            heightmapOptions, terrainPath.string());
    notes = samples.notes;
    field = heightSampleField(samples);
  }
  field.uniformTolerance = o.errorM;
  const tin::Track track = placeTrack(trackObj, field, o, trackPath.string());
  const tin::Tin terrainTin = tin::buildTin(field, {});
  tin::OverlayResult r;
  try {
    r = tin::overlayTrack(field, terrainTin, track, o.mode);
  } catch (const core::InputError& e) {
    throw core::InputError(trackPath.string() + ": " + e.what());
  }

  const tin::WeldedMesh welded = tin::weldTin(field, r.tin);
  const tin::MeshTopology top = tin::meshTopology(welded.vertices, welded.triangles);
  MeshData mesh;
  mesh.positions.assign(welded.vertices, Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < r.tin.xy.size(); ++v)
    mesh.positions[welded.vertexOf[v]] = r.positions[v];
  std::size_t onTrack = 0;
  for (std::size_t k = 0; k < welded.triangles.size(); ++k) {
    const auto& t = welded.triangles[k];
    mesh.indices.insert(mesh.indices.end(), t.begin(), t.end());
    const std::uint8_t g = r.onTrack[welded.sourceTriangle[k]];
    mesh.triangleGroup.push_back(g);
    onTrack += g;
  }
  mesh.groupNames = {"terrain", "track"};
  const bool stitch = o.mode == tin::OverlayMode::kStitch;
  mesh.description = "PlanetSculpt TIN with a track " +
                     std::string(stitch ? "stitched" : "stenciled") +
                     " in: " + std::to_string(welded.vertices) + " vertices, " +
                     std::to_string(welded.triangles.size()) + " triangles, metres";
  const tin::OverlayReport& rep = r.report;
  nlohmann::json summary = {{"file", out.string()},
                            {"format", toString(format)},
                            {"mode", stitch ? "stitch" : "stencil"},
                            {"error_m", o.errorM},
                            {"terrain_tin_vertices", rep.terrainVertices},
                            {"track_vertices", rep.trackVertices},
                            {"track_triangles", rep.trackTriangles},
                            {"track_triangles_clipped", rep.clippedTrackTriangles},
                            {"vertices", welded.vertices},
                            {"triangles", welded.triangles.size()},
                            {"track_group_triangles", onTrack},
                            {"euler", top.euler()},
                            {"border_edges", top.borderEdges},
                            {"non_manifold_edges", top.nonManifoldEdges}};
  if (stitch) {
    summary["crossing_vertices"] = rep.crossingVertices;
    summary["added_vertex_error_m"] = rep.addedVertexErrorM;
  } else {
    summary["removed_terrain_vertices"] = rep.removedTerrainVertices;
    summary["refill_vertices"] = rep.refillVertices;
    summary["footprint_error_m"] = rep.footprintErrorM;
    summary["outside_error_ratio"] = rep.outsideErrorRatio;
  }
  switch (meshFormatOf(format)) {
    case MeshFormat::kObj:
      writeObjFile(mesh, out);
      break;
    case MeshFormat::kPly:
      writePlyFile(mesh, out);
      break;
    case MeshFormat::kGlb:
      writeGlbFile(mesh, out, nlohmann::json({{"planetsculpt", {{"overlay", summary}}}}).dump());
      break;
  }
  return summary;
}

}  // namespace ps::io
