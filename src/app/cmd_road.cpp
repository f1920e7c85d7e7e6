// `planetsculpt road STROKES --width M --out ROAD.obj [--stroke N] [--planet P]`: a stroke
// sculpted in a recording (a replay's log.jsonl) or of a stroke file as a strip of the given width:
// a road mesh that `overlay ... --at PLACE` stitches or stencils into a planet's TIN (a sphere's,
// a torus's or a cylinder's: on those from a replay's log or a stroke file of `xyz=` points).
// `track`, its name before issue 44 (which keeps "track" for markers), still runs it and says so.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>

#include "app/command_registry.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "edit/stroke_script.hpp"
#include "io/heightmap_import.hpp"
#include "io/mesh_writers.hpp"
#include "io/planet_file.hpp"
#include "io/road_placement.hpp"
#include "tin/strip.hpp"

namespace ps::app {

namespace {

struct RoadArgs {
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

// A surface with no latitude and longitude (a torus, a cylinder) takes a stroke file whose
// points are all `xyz=` points of the planet frame (what the recorder writes); a LAT LON point
// is refused naming its line, as a stroke script's replay refuses it there.
void requirePlanetFramePoints(const edit::StrokeScript& script, const std::string& chartName) {
  using K = edit::ScriptCommand::Kind;
  for (const auto& c : script.commands) {
    if ((c.kind == K::kStroke || c.kind == K::kTo || c.kind == K::kStamp) && !c.point.xyz)
      throw core::InputError(script.source + ":" + std::to_string(c.line) +
                             ": a LAT LON point needs a sphere, and this planet's " + chartName +
                             " chart is none: give the points as xyz=X,Y,Z (metres), or give "
                             "the replay's log.jsonl");
  }
}

// A replay's log (`replay`/`demo` write OUT/log.jsonl, one line per frame): each stroke the
// frames from its "begin" through its "move"s, at their control vertices on the planet.
std::vector<std::vector<Eigen::Vector3d>> logPaths(const std::string& file,
                                                   const terrain::Terrain& planet) {
  std::ifstream in(file);
  std::vector<std::vector<Eigen::Vector3d>> paths;
  std::string line;
  int lineNo = 0;
  const int side = planet.grid().side();
  while (std::getline(in, line)) {
    ++lineNo;
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object())
      throw core::InputError(file + ":" + std::to_string(lineNo) + ": not a JSON object");
    const std::string stroke = j.value("stroke", "");
    if ((stroke != "begin" && stroke != "move") || !j.contains("control_vertex")) continue;
    const auto& c = j["control_vertex"];
    if (!c.is_array() || c.size() != 2 || !c[0].is_number_integer() || !c[1].is_number_integer() ||
        c[0].get<int>() < 0 || c[0].get<int>() >= side || c[1].get<int>() < 0 ||
        c[1].get<int>() >= side)
      throw core::InputError(file + ":" + std::to_string(lineNo) +
                             ": control_vertex is not a vertex of the planet's " +
                             planet.grid().label() + " grid (another planet's log?)");
    const Eigen::Vector3d p = planet.chart().position(c[0].get<int>(), c[1].get<int>(), 0.0);
    if (stroke == "begin" || paths.empty()) paths.emplace_back();
    paths.back().push_back(p);
  }
  return paths;
}

int runRoad(const RoadArgs& a) {
  std::unique_ptr<terrain::Terrain> planet;
  double radius = io::kDefaultImportRadius;
  const bool replayLog = std::filesystem::path(a.strokes).extension() == ".jsonl";
  std::optional<edit::StrokeScript> script;
  if (!replayLog) script = edit::loadStrokeScript(a.strokes);
  if (!a.planet.empty()) {
    planet = io::loadPlanet(a.planet);
    const bool sphere = planet->chart().sphereRadius() > 0;
    if (!sphere && script) requirePlanetFramePoints(*script, planet->chart().name());
    if (sphere) radius = planet->chart().sphereRadius();
  }
  if (replayLog && !planet)
    throw core::InputError(a.strokes +
                           ": a replay's log names grid vertices: give --planet (the "
                           "planet the replay sculpted, OUT/planet.planet)");
  // Without a planet the stroke file's sphere of the default radius.
  const core::LatLongChart fileSphere(core::GridSize(5), radius);
  const core::Chart& chart = planet ? planet->chart() : fileSphere;
  const auto paths = replayLog ? logPaths(a.strokes, *planet) : strokePaths(*script, radius);
  if (a.stroke < 1 || a.stroke > int(paths.size()))
    throw core::InputError(a.strokes + ": --stroke " + std::to_string(a.stroke) +
                           ": the file has " + std::to_string(paths.size()) + " strokes");
  const auto& path = paths[std::size_t(a.stroke - 1)];
  // The road's frame: the tangent plane at the stroke's start (x east, y north), each point
  // taken onto it along the surface's normal (on a sphere through its centre), as `overlay --at`
  // puts them back (io/road_placement).
  std::array<double, 2> place;
  try {
    place = io::placeOf(chart, path.front());
  } catch (const core::InputError& e) {
    throw core::InputError(a.planet + ": " + e.what());
  }
  const io::RoadFrame frame = io::roadFrame(chart, {place[0], place[1], 0}, a.strokes);
  std::vector<Eigen::Vector2d> centre;
  double length = 0;
  for (const Eigen::Vector3d& p : path) {
    const Eigen::Vector3d n = io::surfaceNormal(chart, p);
    if (n.dot(frame.up) < 0.2)
      throw core::InputError(a.strokes + ": stroke " + std::to_string(a.stroke) +
                             " turns more than 78 degrees from its start; one road cannot hold it");
    const Eigen::Vector3d q = p + n * ((frame.origin - p).dot(frame.up) / n.dot(frame.up));
    const Eigen::Vector2d local((q - frame.origin).dot(frame.x), (q - frame.origin).dot(frame.y));
    if (!centre.empty()) length += (local - centre.back()).norm();
    centre.push_back(local);
  }
  const tin::Strip strip = tin::stripAlong(centre, a.width);
  io::MeshData mesh;
  for (const Eigen::Vector2d& v : strip.xy) {
    double z = 0;
    if (planet) {
      const auto uv = chart.inverse(frame.at({v.x(), v.y(), 0}));
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
  char at[96];
  std::snprintf(at, sizeof at, "%.10g,%.10g,0", place[0], place[1]);
  mesh.description =
      "PlanetSculpt road: stroke " + std::to_string(a.stroke) + " of " + a.strokes + ", " +
      core::exactNumber(a.width) + " m wide; x east, y north in metres on the tangent plane at " +
      std::string(at) + " (overlay --at " + std::string(at) + "); z height above the datum";
  io::writeObjFile(mesh, a.output);
  const nlohmann::json summary = {{"file", a.output},
                                  {"stroke", a.stroke},
                                  {"points", strip.xy.size() / 2},
                                  {"length_m", length},
                                  {"width_m", a.width},
                                  {"vertices", strip.xy.size()},
                                  {"triangles", strip.triangles.size()},
                                  {"heights", planet ? "the planet's" : "0 (no --planet)"},
                                  {"at", at}};
  std::cout << summary.dump() << "\n";
  return 0;
}

void addRoadOptions(CLI::App& sub, RoadArgs& a) {
  sub.add_option("strokes", a.strokes,
                 "A replay's log (OUT/log.jsonl of `replay`/`demo`: the strokes sculpted in the "
                 "recording; needs --planet) or a stroke file (data/demo-strokes.txt, ...)")
      ->required();
  sub.add_option("--out", a.output, "Road mesh (.obj)")->required();
  sub.add_option("--width", a.width, "Strip width in metres")->required();
  sub.add_option("--stroke", a.stroke, "Which stroke, counted from 1")->capture_default_str();
  sub.add_option("--planet", a.planet,
                 "The planet the strokes were sculpted on: its radius, and the strip's heights "
                 "(else the default radius and heights 0)");
}

const CommandRegistration kRoad([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<RoadArgs>();
  sub = root.add_subcommand("road",
                            "A stroke of a stroke file as a strip (a road mesh OBJ for `overlay`)");
  addRoadOptions(*sub, *a);
  return [a] { return runRoad(*a); };
});

// The old name: the same options and output, and one line on stderr saying it is deprecated.
const CommandRegistration kTrackAlias([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto a = std::make_shared<RoadArgs>();
  sub = root.add_subcommand("track", "Deprecated: the old name of `road` (the same options)");
  addRoadOptions(*sub, *a);
  return [a] {
    std::cerr << "planetsculpt: `track` is deprecated, use `planetsculpt road` (the same "
                 "options; \"track\" now names marker tracking only)\n";
    return runRoad(*a);
  };
});

}  // namespace
}  // namespace ps::app
