#pragma once
// Rigid sets of markers: the planet board (several tags around the planet's footprint) and the
// tool solids (tags on several faces), as data. A layout file is JSON:
//
//   {"family": "tag36h11", "units": "m",
//    "markers": [{"id": N, "corners": [[x,y,z], [x,y,z], [x,y,z], [x,y,z]]}, ...],
//    "planet_centre": [x,y,z],     (boards: where the planet's centre sits, default size)
//    "tip": [x,y,z],               (tools: the tip)
//    "stick_radius": r,            (tools, optional: the stick from the solid to the tip is a
//    "stick_tip_radius": r}         cone of these radii at the solid and at the tip; default
//                                   4 mm, the tip's radius the stick's; tool_shape.hpp)
//
// Corners are TL, TR, BR, BL of each marker's canonical image (marker_family.hpp), in the
// body's frame (metres; "units": "mm" is read and scaled). A marker's own frame follows from
// its corners as docs/TRACKING.md defines it: x from TL to TR, y from BL to TL, z = x × y out of
// the printed face, origin at the centre. A single marker is the layout of one centred marker.
#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "tracking/pose.hpp"

namespace ps::tracking {

struct LayoutMarker {
  int id = -1;
  std::array<Eigen::Vector3d, 4> corners;  // TL, TR, BR, BL in the body's frame (m)
  double edge() const;                     // mean edge length (m)
  // The marker's frame in the body's frame: X_body = inBody.apply(X_marker).
  Pose inBody() const;
};

// A tool's stick when its layout file names no radius: a 8 mm dowel or pencil.
constexpr double kDefaultStickRadius = 0.004;
// Radii above this (m) are refused: a stick thicker than a broom handle is a typo.
constexpr double kMaxStickRadius = 0.02;

struct MarkerLayout {
  std::string family = "tag36h11";
  std::vector<LayoutMarker> markers;
  std::optional<Eigen::Vector3d> planetCentre;  // boards
  std::optional<Eigen::Vector3d> tip;           // tools
  // The stick's radius at the solid and at the tip (m), when the file gives them (tools only).
  std::optional<double> stickRadius, stickTipRadius;
  std::string source;  // file name, for messages

  // The stick's radii with their defaults: kDefaultStickRadius, the tip's the stick's.
  double stickBaseRadius() const;
  double stickEndRadius() const;

  const LayoutMarker* find(int id) const;
  std::vector<int> ids() const;
  // Whether every marker lies in one plane (a board: its pose has the planar flip ambiguity).
  bool planar() const;

  // One marker of edge `size` centred at the origin with the marker's own axes.
  static MarkerLayout singleMarker(int id, double size, const std::string& family = "tag36h11");
};

// Throws core::InputError "SOURCE: markers[i] (id N): ..." for anything malformed: not JSON, a
// missing or mistyped field, units other than m or mm, an unknown family, an id outside the
// family, duplicate ids, corners that are not a planar square (edges and diagonals equal and
// the four corners in one plane, within 0.5 % of the edge), a stick radius that is not a number
// in (0, 20 mm] or is given without a tip.
MarkerLayout parseMarkerLayout(const nlohmann::json& j, const std::string& source);
MarkerLayout loadMarkerLayout(const std::filesystem::path& path);
nlohmann::json toJson(const MarkerLayout& layout);  // units m

// The layout in another family and at another size (what `planetsculpt markers` prints and writes
// beside its sheets): the family replaced (empty: as it is) and every marker and the planet's
// centre scaled about the body's origin so that the markers' mean edge is `markerEdge` (m; 0:
// as it is); a solid's (a cube's) faces moved along their normals so that they still just hold
// their markers with the new family's quiet zone, the tip scaled with them. Checked as a layout
// file is: InputError "SOURCE: ..." for an id the new family does not hold, or a size that is not >
// 0.
MarkerLayout resizedLayout(const MarkerLayout& layout, const std::string& family,
                           double markerEdge);
// The layout file's text: the committed files' style (one marker a line, metres rounded to the
// nanometre), what loadMarkerLayout reads back.
std::string layoutFileText(const MarkerLayout& layout);

// The committed layouts (markers/planet-board.json, markers/tool-cube.json) under `root`.
std::filesystem::path defaultBoardPath(const std::filesystem::path& root);
std::filesystem::path defaultToolLayoutPath(const std::filesystem::path& root);

}  // namespace ps::tracking
