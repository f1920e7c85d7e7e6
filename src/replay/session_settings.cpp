#include "replay/session_timeline.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "core/chart_factory.hpp"
#include "core/input_error.hpp"
#include "io/stroke_journal.hpp"
#include "tracking/marker_layout.hpp"

namespace ps::replay {

SessionSettings SessionSettings::of(const ReplayOptions& o) {
  SessionSettings s;
  s.tool = o.tool;
  s.brush = o.brush;
  s.displace = o.displace;
  s.pressDepth = o.pressDepth;
  s.planetRadius = o.scene.planetRadius;
  return s;
}

Eigen::Matrix3d SessionSettings::rotation() const {
  const double deg = std::numbers::pi / 180;
  return (Eigen::AngleAxisd(tiltDeg * deg, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(spinDeg * deg, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

void SessionSettings::validate() const {
  ReplayOptions o;
  o.tool = tool;
  o.brush = brush;
  o.displace = displace;
  o.pressDepth = pressDepth;
  o.scene.planetRadius = planetRadius;
  o.validate();
  if (!(std::isfinite(spinDeg) && std::isfinite(tiltDeg)))
    throw core::InputError("planet turn (spin, tilt) is not finite");
}

nlohmann::json toJson(const SessionSettings& s) {
  return {{"tool", toString(s.tool)},
          {"brush_radius_m", s.brush.radius},
          {"sigma", s.brush.sigma},
          {"mu", s.brush.mu},
          {"mode", edit::toString(s.brush.mode)},
          {"strength_m", s.brush.strength},
          {"rate", s.brush.rate},
          {"target_m", s.brush.target},
          {"spacing", s.brush.spacing},
          {"displace_radius_m", s.displace.radius},
          {"rampart_width", s.displace.rampartWidth},
          {"displace_spacing", s.displace.spacing},
          {"press_m", s.pressDepth},
          {"material", s.displace.material.name},
          {"planet_radius_m", s.planetRadius},
          {"spin_deg", s.spinDeg},
          {"tilt_deg", s.tiltDeg}};
}

nlohmann::json diff(const SessionSettings& before, const SessionSettings& after) {
  const nlohmann::json a = toJson(before), b = toJson(after);
  nlohmann::json d = nlohmann::json::object();
  for (const auto& [key, value] : b.items())
    if (a.at(key) != value) d[key] = value;
  return d;
}

SessionStart SessionStart::of(const terrain::Terrain& planet, const std::string& planetFile,
                              int gridSide, std::uint64_t seed,
                              const tracking::CameraCalibration& calib,
                              const std::string& calibrationFile, const ReplayOptions& o,
                              double fps, std::size_t undoSteps) {
  SessionStart s;
  s.planetFile = planetFile;
  s.gridSide = gridSide;
  s.seed = seed;
  s.chart = planet.chart().name();
  const core::ChartDims dims = core::dimsOf(planet.chart());
  s.radius = dims.radius;  // a sphere's radius() itself
  s.minorRadius = dims.minorRadius;
  s.length = dims.length;
  s.heightsCrc = io::heightsChecksum(planet.heights());
  s.calibrationFile = calibrationFile;
  s.imageSize = calib.imageSize;
  for (int i = 0; i < 9; ++i) s.K.push_back(calib.K(i / 3, i % 3));
  for (int i = 0; i < int(calib.distortion.total()); ++i)
    s.distortion.push_back(calib.distortion.at<double>(i));
  s.fps = fps;
  s.family = o.detector.family;
  s.decimate = o.detector.decimate;
  s.planetId = o.scene.planet.id;
  s.planetMarkerSize = o.scene.planet.size;
  s.toolId = o.scene.tool.id;
  s.toolMarkerSize = o.scene.tool.size;
  s.tipOffset = o.scene.tipOffset;
  s.board = o.scene.planet.layout;
  s.toolLayout = o.scene.tool.layout;
  s.touchDistance = o.scene.touchDistance;
  s.filter = o.scene.planet.filter && o.scene.tool.filter && o.scene.filterTip;
  s.settle = o.settle;
  s.undoSteps = undoSteps;
  return s;
}

void SessionStart::applyTo(ReplayOptions& o) const {
  o.detector.family = family;
  o.detector.decimate = decimate;
  o.scene.planet.id = planetId;
  o.scene.planet.size = planetMarkerSize;
  o.scene.tool.id = toolId;
  o.scene.tool.size = toolMarkerSize;
  o.scene.useBoard(board);
  o.scene.useToolLayout(toolLayout);
  o.scene.tipOffset = tipOffset;
  o.scene.touchDistance = touchDistance;
  o.scene.planet.filter = o.scene.tool.filter = o.scene.filterTip = filter;
  o.settle = settle;
}

nlohmann::json toJson(const SessionStart& s) {
  nlohmann::json j = {{"planet",
                       {{"file", s.planetFile},
                        {"grid", s.gridSide},
                        {"seed", s.seed},
                        {"chart", s.chart},
                        {"radius_m", s.radius},
                        {"heights_crc32", s.heightsCrc}}},
                      {"calibration",
                       {{"file", s.calibrationFile},
                        {"width", s.imageSize.width},
                        {"height", s.imageSize.height},
                        {"K", s.K},
                        {"distortion", s.distortion}}},
                      {"fps", s.fps},
                      {"markers",
                       {{"family", s.family},
                        {"decimate", s.decimate},
                        {"planet_id", s.planetId},
                        {"planet_marker_m", s.planetMarkerSize},
                        {"tool_id", s.toolId},
                        {"tool_marker_m", s.toolMarkerSize},
                        {"tip_m", {s.tipOffset.x(), s.tipOffset.y(), s.tipOffset.z()}},
                        {"touch_m", s.touchDistance},
                        {"filter", s.filter}}},
                      {"settle", s.settle},
                      {"undo_steps", s.undoSteps}};
  // Only a torus's and a cylinder's: a sphere's sidecar stays as it was, byte for byte.
  if (s.minorRadius > 0) j["planet"]["minor_radius_m"] = s.minorRadius;
  if (s.length > 0) j["planet"]["length_m"] = s.length;
  if (s.board) j["markers"]["board"] = tracking::toJson(*s.board);
  if (s.toolLayout) j["markers"]["tool_layout"] = tracking::toJson(*s.toolLayout);
  return j;
}

}  // namespace ps::replay
