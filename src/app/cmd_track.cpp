// `planetsculpt track STROKES --width M --out TRACK.obj [--stroke N] [--planet P]`: a stroke of
// a stroke file (a sculpted session's journal, `demo`'s strokes) as a strip of the given width:
// a track mesh that `overlay ... --at LAT,LON` stitches or stencils into a planet's TIN.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>

#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "edit/stroke_script.hpp"
#include "io/heightmap_import.hpp"
#include "io/mesh_writers.hpp"
#include "io/planet_file.hpp"
#include "tin/strip.hpp"

namespace ps::app {

namespace {

struct TrackArgs {
  std::string strokes, output, planet;
  double width = 0;
  int stroke = 1;
};

// The stroke file's strokes, each the positions of its `stroke` and `to` points.
std::vector<std::vector<Eigen::Vector3d>> strokePaths(const edit::StrokeScript& script,
                                                      double radius) {
  std::vector<std::vector<Eigen::Vector3d>> paths;
  bool open = false;
  for (const auto& c : script.commands) {
    using K = edit::ScriptCommand::Kind;
    if (c.kind == K::kStroke) {
      paths.push_back({edit::scriptPosition(c.point, radius)});
      open = true;
    } else if (c.kind == K::kTo && open) {
      paths.back().push_back(edit::scriptPosition(c.point, radius));
    } else if (c.kind == K::kEnd) {
      open = false;
    }
  }
  return paths;
}

int runTrack(const TrackArgs& a) {
  const edit::StrokeScript script = edit::loadStrokeScript(a.strokes);
  std::unique_ptr<terrain::Terrain> planet;
  double radius = io::kDefaultImportRadius;
  if (!a.planet.empty()) {
    planet = io::loadPlanet(a.planet);
    if (!planet->chart().hasPoleRows())
      throw core::InputError(a.planet + ": a stroke's track needs a planet (a lat-long chart)");
    radius = planet->chart().radius();
  }
  const auto paths = strokePaths(script, radius);
  if (a.stroke < 1 || a.stroke > int(paths.size()))
    throw core::InputError(a.strokes + ": --stroke " + std::to_string(a.stroke) +
                           ": the file has " + std::to_string(paths.size()) + " strokes");
  const auto& path = paths[std::size_t(a.stroke - 1)];
  // The track's frame: the tangent plane at the stroke's start (x east, y north), points taken
  // onto it through the planet's centre, as `overlay --at` puts them back.
  const Eigen::Vector3d up = path.front().normalized();
  const Eigen::Vector3d east = Eigen::Vector3d::UnitZ().cross(up).norm() > 1e-9
                                   ? Eigen::Vector3d::UnitZ().cross(up).normalized()
                                   : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d north = up.cross(east);
  std::vector<Eigen::Vector2d> centre;
  double length = 0;
  for (const Eigen::Vector3d& p : path) {
    const Eigen::Vector3d d = p.normalized();
    if (d.dot(up) < 0.2)
      throw core::InputError(
          a.strokes + ": stroke " + std::to_string(a.stroke) +
          " reaches more than 78 degrees from its start; one track cannot hold it");
    const Eigen::Vector3d q = radius * d / d.dot(up) - radius * up;
    if (!centre.empty())
      length += (Eigen::Vector2d(q.dot(east), q.dot(north)) - centre.back()).norm();
    centre.emplace_back(q.dot(east), q.dot(north));
  }
  const tin::Strip strip = tin::stripAlong(centre, a.width);
  io::MeshData mesh;
  for (const Eigen::Vector2d& v : strip.xy) {
    double z = 0;
    if (planet) {
      const auto uv = planet->chart().inverse(radius * up + v.x() * east + v.y() * north);
      if (uv) {
        const int m = planet->grid().m();
        const int u0 = std::min(int(uv->x()), m - 1), v0 = std::min(int(uv->y()), m - 1);
        const double fu = uv->x() - u0, fv = uv->y() - v0;
        z = (1 - fv) * ((1 - fu) * planet->height(u0, v0) + fu * planet->height(u0 + 1, v0)) +
            fv * ((1 - fu) * planet->height(u0, v0 + 1) + fu * planet->height(u0 + 1, v0 + 1));
      }
    }
    mesh.positions.emplace_back(v.x(), v.y(), z);
  }
  for (const auto& t : strip.triangles) mesh.indices.insert(mesh.indices.end(), t.begin(), t.end());
  const double lat = std::asin(std::clamp(up.z(), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  const double lon = std::atan2(up.y(), up.x()) * 180.0 / std::numbers::pi;
  char at[96];
  std::snprintf(at, sizeof at, "%.10g,%.10g,0", lat, lon);
  mesh.description =
      "PlanetSculpt track: stroke " + std::to_string(a.stroke) + " of " + a.strokes + ", " +
      core::exactNumber(a.width) + " m wide; x east, y north in metres on the tangent plane at " +
      std::string(at) + " (overlay --at " + std::string(at) + "); z height above the datum";
  io::writeObjFile(mesh, a.output);
  const nlohmann::json summary = {{"file", a.output},
                                  {"stroke", a.stroke},
                                  {"points", centre.size()},
                                  {"length_m", length},
                                  {"width_m", a.width},
                                  {"vertices", strip.xy.size()},
                                  {"triangles", strip.triangles.size()},
                                  {"heights", planet ? "the planet's" : "0 (no --planet)"},
                                  {"at", at}};
  std::cout << summary.dump() << "\n";
  return 0;
}

const CommandRegistration kTrack([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<TrackArgs>();
  sub = root.add_subcommand(
      "track", "A stroke of a stroke file as a strip (a track mesh OBJ for `overlay`)");
  sub->add_option("strokes", a->strokes,
                  "Stroke file (a session's journal script, data/demo-strokes.txt, ...)")
      ->required();
  sub->add_option("--out", a->output, "Track mesh (.obj)")->required();
  sub->add_option("--width", a->width, "Strip width in metres")->required();
  sub->add_option("--stroke", a->stroke, "Which stroke, counted from 1")->capture_default_str();
  sub->add_option("--planet", a->planet,
                  "The planet the strokes were sculpted on: its radius, and the strip's heights "
                  "(else the default radius and heights 0)");
  return [a] { return runTrack(*a); };
});

}  // namespace
}  // namespace ps::app
