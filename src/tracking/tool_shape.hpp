#pragma once
// The tracked tool's shape, for what it hides (render: the tool's depth pass, docs/RENDERING.md):
// the solid that carries its markers and the stick from the solid to the tip.
//   * the solid: the box that holds the layout's markers with their quiet zones (what
//     `planetsculpt markers` prints and `synth` draws: a 40 mm tag36h11 marker on each face of a
//     50 mm cube); a single marker's card is the marker with its quiet zone and two cells of
//     margin (the printed tool marker's, and synth's card), 1 mm thick;
//   * the stick: a cone from where the line from the body's origin to the tip leaves the solid
//     to the tip, of the layout's stick radii (marker_layout.hpp: "stick_radius",
//     "stick_tip_radius"; a single marker's 5 mm and 2 mm, as synth draws it).
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "tracking/marker_layout.hpp"
#include "tracking/pose.hpp"
#include "tracking/tracker.hpp"

namespace ps::tracking {

struct ToolShape {
  // The solid: a box along the body's axes (body frame, m).
  Eigen::Vector3d boxCentre = Eigen::Vector3d::Zero();
  Eigen::Vector3d boxHalf = Eigen::Vector3d::Zero();
  // The stick (body frame, m); none when the tip lies inside the solid.
  Eigen::Vector3d stickBase = Eigen::Vector3d::Zero();
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  double baseRadius = 0, tipRadius = 0;
  bool hasStick() const { return (tip - stickBase).norm() > 1e-6; }
};

// The axis-aligned box (body frame) of a layout's markers, each grown about its centre by `grow`
// (the family's total cells over its edge cells: the printed quiet zone): the printed solid.
struct MarkerBox {
  Eigen::Vector3d lo, hi;
};
MarkerBox markersBox(const MarkerLayout& layout, double grow);

// `marginCells`: cells of margin around each marker's quiet zone (0 for a solid's faces).
ToolShape toolShape(const MarkerLayout& layout, const Eigen::Vector3d& tip, double marginCells = 0);
// The scene's tool: its layout (tool solid) or the single marker of `family` (the detector's)
// with its card; the tip at the scene's tipOffset.
ToolShape toolShape(const SceneConfig& scene, const std::string& family = "tag36h11");

// The shape as triangles (3 points each; the box's 12, the cone's side and its ends in
// `segments` steps), each point mapped into a target frame: scale * bodyToTarget.apply(x).
// Closed surfaces: what lies behind them is hidden whatever their winding.
std::vector<Eigen::Vector3d> toolTriangles(const ToolShape& shape, const Pose& bodyToTarget,
                                           double scale = 1, int segments = 24);

// Whether the tool, posed at `tool` (camera-from-body), covers part of a marker's outline as the
// camera sees it: its solid or its stick comes within `bandCells` of the marker's cells
// (`edgeCells` to its edge) of any edge of the quad `corners` (pixels, the detection's). A
// marker's corners are fit to its black border's outer edge: whatever lies over that edge or the
// quiet zone beside it (a dark stick joins the border, a card's edge cuts it) drags them while
// the tag still decodes, and four corners (two numbers more than a pose has) take the error
// into a pose with a small reprojection error, often the planar pose's mirror image. What lies
// over the marker's inside only (its bits) leaves the corners where they were.
bool toolCoversMarkerOutline(const ToolShape& shape, const Pose& tool,
                             const CameraCalibration& calib,
                             const std::array<cv::Point2d, 4>& corners, int edgeCells,
                             double bandCells = 0.25);

}  // namespace ps::tracking
