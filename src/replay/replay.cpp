#include "replay/replay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/chart_factory.hpp"
#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "edit/control_vertex.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/surface_height.hpp"
#include "sand/tin_sand_tool.hpp"
#include "tracking/body_pose.hpp"
#include "tracking/camera_motion.hpp"
#include "tracking/plane_tracker.hpp"

namespace ps::replay {

namespace {

double round6(double v) {
  return std::round(v * 1e6) / 1e6;
}
nlohmann::json vec(const Eigen::Vector3d& v) {
  return {round6(v.x()), round6(v.y()), round6(v.z())};
}

nlohmann::json markerJson(const tracking::MarkerEstimate& m) {
  nlohmann::json j = {{"state", tracking::toString(m.state)}};
  if (m.usable()) {
    j["rvec"] = vec(m.pose.rvec());
    j["tvec"] = vec(m.pose.t);
  }
  if (m.measured && m.ids.size() > 1) j["ids"] = m.ids;
  if (m.heldStill) j["held_still"] = true;
  if (m.carried) j["carried"] = true;
  if (m.measured) {
    j["reprojection_px"] = std::round(m.rms * 1000) / 1000;
    if (std::isfinite(m.ratio)) j["ambiguity_ratio"] = std::round(m.ratio * 100) / 100;
    if (m.byContinuity) j["by_continuity"] = true;
  }
  return j;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

constexpr core::NameTable<ReplayTool, 3> kReplayTools{"replay tool",
                                                      {{{ReplayTool::kBrush, "brush"},
                                                        {ReplayTool::kDisplace, "displace"},
                                                        {ReplayTool::kTinSand, "tin-sand"}}}};

std::string toString(ReplayTool t) {
  return kReplayTools.nameOf(t);
}

ReplayTool replayToolFromString(const std::string& s) {
  return kReplayTools.parse(s);
}

sand::DisplacementSettings ReplayOptions::defaultDisplacement() {
  sand::DisplacementSettings d;
  d.radius = 400e3;
  d.rampartWidth = 0.5;
  return d;
}

edit::BrushSettings ReplayOptions::defaultBrush() {
  edit::BrushSettings b;
  b.radius = 250e3;
  b.strength = 600.0;
  return b;
}

void ReplayOptions::validate() const {
  detector.validate();
  scene.validate();
  brush.validate();
  displace.validate();
  settling.validate();
  if (!(std::isfinite(pressDepth) && pressDepth > 0 && pressDepth <= 2 * displace.radius))
    throw core::InputError("press depth = " + std::to_string(pressDepth) +
                           " m is not in (0, 2 x displacement radius]");
  if (!(fallbackFps > 0 && fallbackFps <= 1000))
    throw core::InputError("fps = " + std::to_string(fallbackFps) + " is not in (0, 1000]");
  if (maxFrames < 0)
    throw core::InputError("max frames = " + std::to_string(maxFrames) + " is negative");
}

struct FrameStepper::Parts {
  std::unique_ptr<tracking::Detector> detector;
  tracking::SceneTracker scene;
  edit::EditPipeline pipeline;
  std::optional<edit::GaussianBrush> brush;
  std::optional<sand::Settler> settler;
  std::optional<sand::DisplacementTool> displacer;
  std::optional<sand::TinSandTool> tinSand;
  // The view's patch of the TIN tool's region, and what it was made at (viewPatch()).
  std::shared_ptr<const terrain::MeshPatch> patch;
  std::uint64_t patchRevision = 0;
  std::size_t patchStamps = 0;
  const sand::TinSandTool* patchTool = nullptr;
  // Boards: whether the camera stood still while the board is hidden (tracker.hpp).
  std::optional<tracking::CameraMotionJudge> motion;
  // Boards: the board's pose from the table around it while it is hidden and the camera moves.
  std::optional<tracking::PlaneTracker> plane;
  tracking::Pose boardPlane;  // board-from-plane
  // The planet had a pose after the last frame: only then can the camera's stillness keep it
  // (once lost, it waits for the board; judging the camera then was work thrown away).
  bool planetHadPose = false;
  // What the frame says of the board when none of its markers was read (tracker.hpp), and the
  // log's camera_shift_px and plane entries.
  tracking::BoardHint boardHint(const cv::Mat& grey, const std::vector<tracking::Detection>& found,
                                const tracking::CameraCalibration& calib, nlohmann::json& log);
  // The board's last measured pose (camera-from-body): where its markers are while the camera
  // stands and they are covered.
  std::optional<tracking::Pose> boardMeasured;
  // Tells the detector where the covered board's markers are in the next frame, while a pose
  // carries them (the plane's, or the last measured one while the camera stands): it searches
  // there every frame and the whole frame less often (DetectorConfig::expectedSearchEvery).
  void expectBoard(const tracking::BoardHint& hint, const tracking::SceneFrame& f,
                   const tracking::CameraCalibration& calib);
  tracking::ToolShape toolShape;  // the tool's solid and stick in its body frame
  Parts(std::unique_ptr<tracking::Detector> d, const tracking::SceneConfig& sc,
        terrain::Terrain& planet)
      : detector(std::move(d)), scene(sc), pipeline(planet) {}
  const edit::Tool& tool(ReplayTool t) const {
    if (t == ReplayTool::kBrush) return *brush;
    if (t == ReplayTool::kTinSand) return *tinSand;
    return *displacer;
  }
};

FrameStepper::FrameStepper(const tracking::CameraCalibration& calib, terrain::Terrain& planet,
                           const ReplayOptions& options)
    : o_(options), calib_(calib), planet_(planet) {
  o_.validate();
  // One detector config per family that the board and the tool name: a layout file names its
  // own family, single markers are of the configured one.
  std::vector<tracking::DetectorConfig> families;
  auto configFor = [&](const std::string& family) -> tracking::DetectorConfig& {
    for (auto& c : families)
      if (c.family == family) return c;
    families.push_back(o_.detector);
    families.back().family = family;
    families.back().ids.clear();
    families.back().sets.clear();
    return families.back();
  };
  for (auto* m : {&o_.scene.planet, &o_.scene.tool}) {
    if (!m->layout) {
      m->family = o_.detector.family;
      configFor(m->family).ids.push_back(m->id);
      continue;
    }
    tracking::DetectorConfig& dc = configFor(m->layout->family);
    for (int id : m->layout->ids()) dc.ids.push_back(id);
    dc.sets.push_back(m->layout->ids());
  }
  o_.scene.validate();  // ids clash within a family only, now that each names its family
  for (const auto& c : families) family_ += (family_.empty() ? "" : ", ") + c.family;
  const core::Chart& chart = planet_.chart();
  // The displayed planetRadius is the planet's bounding sphere (a sphere's own radius, bit for
  // bit; a torus's or a cylinder's sphere about its centre): that sphere stands on the board.
  const double bound = core::boundingRadius(chart);
  if (!(bound > 0))
    throw core::InputError(
        "replay needs a planet with a centre (a sphere, a torus or a cylinder); "
        "a " +
        chart.name() + " planet has none to stand on the board");
  scale_ = bound / o_.scene.planetRadius;
  p_ = std::make_unique<Parts>(tracking::makeDetector(families), o_.scene, planet_);
  p_->toolShape = tracking::toolShape(o_.scene, o_.scene.tool.family);
  if (o_.scene.planet.holdWhileStill) {
    p_->motion.emplace();
    if (o_.scene.planet.layout->planar()) {
      p_->plane.emplace();
      // The plane the board lies on: its first marker's, z = 0.
      p_->boardPlane = o_.scene.planet.layout->markers.front().inBody();
    }
  }
  if (chart.sphereRadius() > 0) {
    p_->scene.setSurface([this](const Eigen::Vector3d& tracked) {
      if (!(tracked.norm() > 0)) return o_.scene.planetRadius;
      const Eigen::Vector3d p =
          rotated_ ? Eigen::Vector3d(userRotation_.transpose() * tracked) : tracked;
      const auto c = edit::nearestVertex(planet_.chart(), p);
      return (planet_.chart().sphereRadius() + planet_.height(c.u, c.v)) / scale_;
    });
  } else {
    // A torus or a cylinder: the height along the surface's normal (edit/surface_height.hpp);
    // where the tip has no nearest vertex (the torus's axis or centre circle, the cylinder's
    // axis) it touches nothing.
    p_->scene.setHeightAbove([this](const Eigen::Vector3d& tracked) {
      const Eigen::Vector3d p =
          rotated_ ? Eigen::Vector3d(userRotation_.transpose() * tracked) : tracked;
      const auto c = edit::surfaceContact(planet_, p * scale_);
      return c ? c->height / scale_ : std::numeric_limits<double>::infinity();
    });
  }
  p_->pipeline.setUndoEnabled(o_.undo);
  rebuildTools();
}

FrameStepper::~FrameStepper() = default;

edit::EditPipeline& FrameStepper::pipeline() {
  return p_->pipeline;
}

double FrameStepper::toolRadius() const {
  return p_->tool(o_.tool).radius();
}

std::shared_ptr<const terrain::MeshPatch> FrameStepper::viewPatch() {
  Parts& p = *p_;
  const sand::TinSandTool* tool =
      o_.tool == ReplayTool::kTinSand && p.tinSand ? &*p.tinSand : nullptr;
  if (!tool || !tool->strokeTin()) {
    p.patch.reset();
    p.patchTool = nullptr;
    return nullptr;
  }
  // The planet's revision and the tool's stamps name what the region and the grid hold.
  if (p.patchTool == tool && p.patchRevision == planet_.revision() &&
      p.patchStamps == tool->stamps())
    return p.patch;
  p.patchTool = tool;
  p.patchRevision = planet_.revision();
  p.patchStamps = tool->stamps();
  p.patch.reset();
  if (tool->strokeTin()->holds(planet_.heights()))
    p.patch = std::make_shared<const terrain::MeshPatch>(tool->strokeTin()->patch());
  return p.patch;
}

void FrameStepper::rebuildTools() {
  endStroke();
  p_->brush.emplace(o_.brush);
  // The sand tools on a chart the sand core does not know are refused when chosen, by
  // SandGrid's message (the TIN sand tool's by its own, as a stamp too large for a surface's
  // curvature); the brush works there.
  const bool sandChart = sand::sandCoreKnows(planet_.chart());
  if (!sandChart && o_.tool == ReplayTool::kBrush) {
    p_->displacer.reset();
    p_->tinSand.reset();
    return;
  }
  const bool wantSettler = o_.tool == ReplayTool::kDisplace && o_.settle;
  if (wantSettler && !p_->settler) {
    p_->settler.emplace(planet_, o_.displace.material, o_.settling);
    p_->settler->attachUndo(&p_->pipeline);  // undoing a sand stroke takes its settling back
  }
  p_->displacer.emplace(planet_.chartPtr(), o_.displace, p_->settler ? &*p_->settler : nullptr);
  if (o_.tool == ReplayTool::kDisplace) p_->displacer->validate();
  // Sand on a TIN: the displacement's radius, spacing and material; it erodes in its TIN.
  sand::TinSandToolSettings tin;
  tin.radius = o_.displace.radius;
  tin.spacing = o_.displace.spacing;
  tin.sand.material = o_.displace.material;
  p_->tinSand.emplace(planet_.chartPtr(), tin);
  if (o_.tool == ReplayTool::kTinSand) p_->tinSand->validate();
}

void FrameStepper::endStroke() {
  if (p_ && p_->pipeline.inStroke()) p_->pipeline.endStroke();
}

void FrameStepper::setUserRotation(const Eigen::Matrix3d& rotation) {
  if (!rotation.allFinite() ||
      !(rotation * rotation.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-9))
    throw core::InputError("planet rotation is not a rotation matrix");
  if (rotation == userRotation_) return;
  endStroke();  // the planet jumps under the tool
  userRotation_ = rotation;
  rotated_ = !rotation.isIdentity(0.0);
}

void FrameStepper::setTool(ReplayTool tool) {
  if (tool == o_.tool) return;
  const ReplayTool before = o_.tool;
  o_.tool = tool;
  try {
    rebuildTools();
  } catch (const core::InputError&) {  // a tool this planet cannot take: keep the one it had
    o_.tool = before;
    rebuildTools();
    throw;
  }
}

void FrameStepper::setPlanetSize(double planetRadiusM) {
  p_->scene.setPlanetRadius(planetRadiusM);  // validates first
  endStroke();
  o_.scene.planetRadius = planetRadiusM;
  scale_ = core::boundingRadius(planet_.chart()) / planetRadiusM;
}

void FrameStepper::setBrush(const edit::BrushSettings& brush) {
  brush.validate();
  o_.brush = brush;
  rebuildTools();
}

void FrameStepper::setDisplacement(const sand::DisplacementSettings& displace, double pressDepth) {
  ReplayOptions o = o_;
  o.displace = displace;
  o.pressDepth = pressDepth;
  o.validate();
  // Another material: what is still settling goes on settling, as the new one (the settler
  // settles one material at a time, docs/SAND.md "The settler").
  if (!(displace.material == o_.displace.material)) {
    endStroke();
    if (p_->settler) p_->settler->setMaterial(displace.material);
  }
  o_ = o;
  rebuildTools();
}

tracking::BoardHint FrameStepper::Parts::boardHint(const cv::Mat& grey,
                                                   const std::vector<tracking::Detection>& found,
                                                   const tracking::CameraCalibration& calib,
                                                   nlohmann::json& log) {
  tracking::BoardHint hint;
  if (!motion) return hint;
  const bool boardSeen = std::any_of(found.begin(), found.end(),
                                     [&](const auto& d) { return scene.config().planet.owns(d); });
  if (boardSeen || !planetHadPose || !motion->hasReference()) return hint;
  // Still (the cheap judge against the last frame with the board): held. Moved: carried by the
  // plane the board lies on, or lost; once the plane carries it, the plane alone decides.
  bool moved = plane && plane->active();
  if (!moved) {
    const tracking::CameraMotion m = motion->judge(grey);
    hint.cameraStill = m.still;
    moved = m.judged && std::isfinite(m.medianShiftPx) && !m.still;
    if (m.judged)
      log["camera_shift_px"] = std::isfinite(m.medianShiftPx)
                                   ? nlohmann::json(std::round(m.medianShiftPx * 100) / 100)
                                   : nlohmann::json("lost");
  }
  if (hint.cameraStill || !plane) {
    hint.cameraMoved = moved;
    return hint;
  }
  std::vector<std::array<cv::Point2d, 4>> toolQuads;
  for (const auto& d : found)
    if (scene.config().tool.owns(d)) toolQuads.push_back(d.corners);
  const tracking::PlaneTrack t = plane->track(grey, calib, toolQuads);
  if (t.ok) {
    hint.carried = t.board * boardPlane.inverse();
    log["plane"] = {{"inliers", t.inliers}, {"rms_px", std::round(t.rmsPx * 1000) / 1000}};
  } else {
    hint.cameraMoved = moved;
    log["plane"] = {{"lost", t.why}};
  }
  return hint;
}

void FrameStepper::Parts::expectBoard(const tracking::BoardHint& hint,
                                      const tracking::SceneFrame& f,
                                      const tracking::CameraCalibration& calib) {
  const auto& layout = scene.config().planet.layout;
  if (!motion || !layout) return;
  if (f.planet.measured) {
    boardMeasured = f.planet.raw;
    return;  // the detector follows the markers it found
  }
  std::optional<tracking::Pose> where = hint.carried;
  if (!where && hint.cameraStill && f.planet.usable()) where = boardMeasured;
  if (!where) return;
  const auto corners = tracking::projectLayout(*layout, *where, calib);
  std::vector<tracking::Detection> expected;
  for (std::size_t i = 0; i < layout->markers.size(); ++i) {
    // In front of the camera (behind it the projection folds back into the image).
    if (!((*where * layout->markers[i].inBody()).t.z() > 0.01)) continue;
    tracking::Detection d;
    d.family = layout->family;
    d.id = layout->markers[i].id;
    d.corners = corners[i];
    expected.push_back(d);
  }
  detector->expect(expected);
}

StepResult FrameStepper::step(const cv::Mat& image, int frame, double time) {
  const core::Chart& chart = planet_.chart();
  const double R = chart.sphereRadius();
  const double scale = scale_;
  const ReplayOptions& o = o_;
  edit::EditPipeline& pipeline = p_->pipeline;
  const edit::Tool& tool = p_->tool(o.tool);
  ReplaySummary& s = s_;
  // Where the tool acts for a tip over planet point p: the brush at p itself; the displacement
  // sphere at a fixed altitude for the whole stroke (a plough), set when the stroke begins so
  // that its lowest point is pressDepth below the surface at that control vertex. (Setting it
  // from the surface under each stamp would dig deeper with every overlapping stamp.)
  auto toolPosition = [&](const Eigen::Vector3d& p, const core::GridPoint& c,
                          bool begin) -> Eigen::Vector3d {
    if (o.tool == ReplayTool::kBrush) return p;
    if (!(R > 0.0)) {
      // A torus or a cylinder: the same plough at a fixed height over the reference surface,
      // along its normal under the tip (strokeAltitude_ is that height here).
      if (begin) strokeAltitude_ = planet_.height(c.u, c.v) - o.pressDepth + o.displace.radius;
      if (const auto uv = chart.inverse(p))
        return chart.positionAt((*uv)(0), (*uv)(1), strokeAltitude_);
      return chart.position(c.u, c.v, strokeAltitude_);
    }
    if (begin) strokeAltitude_ = R + planet_.height(c.u, c.v) - o.pressDepth + o.displace.radius;
    return p.normalized() * strokeAltitude_;
  };

  StepResult out;
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json j = {{"frame", frame}, {"time", std::round(time * 1e6) / 1e6}};
  std::vector<tracking::Detection> found;
  // One grey image for the detector and the camera-motion judge (each would convert again).
  cv::Mat grey;
  try {
    grey = tracking::toGrey(image);
    found = p_->detector->detect(grey);
  } catch (const std::exception& e) {
    j["notes"].push_back(std::string("detection failed: ") + e.what());
  }
  out.times.detectMs = msSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const tracking::BoardHint hint = p_->boardHint(grey.empty() ? image : grey, found, calib_, j);
  out.scene = p_->scene.update(found, calib_, frame, time, hint);
  p_->planetHadPose = out.scene.planet.usable();
  p_->expectBoard(hint, out.scene, calib_);
  if (p_->motion && out.scene.planet.measured) {
    std::vector<std::array<cv::Point2d, 4>> quads, toolQuads;
    for (const auto& d : found) {
      quads.push_back(d.corners);
      if (o_.scene.tool.owns(d)) toolQuads.push_back(d.corners);
    }
    // One copy of the frame kept for both (neither writes into it).
    const cv::Mat& g = grey.empty() ? image : grey;
    const cv::Mat kept = !grey.empty() && grey.data != image.data ? g : g.clone();
    p_->motion->setReference(kept, quads, true);
    if (p_->plane)
      p_->plane->setReference(kept, out.scene.planet.raw * p_->boardPlane, toolQuads, true,
                              int(out.scene.planet.ids.size()));
  }
  if (rotated_) out.scene.tipPlanet = userRotation_.transpose() * out.scene.tipPlanet;
  const tracking::SceneFrame& f = out.scene;
  out.times.trackMs = msSince(t1);
  anyMarker_ = anyMarker_ || !found.empty();
  s.framesWithPlanet += f.planet.usable();
  s.framesPlanetHeld += f.planet.usable() && f.planet.state == tracking::TrackState::kHeld;
  s.framesWithTool += f.tool.usable();
  j["markers"] = found.size();
  j["planet"] = markerJson(f.planet);
  if (f.planetCentreValid) j["planet"]["centre_camera_m"] = vec(f.planetCentreCamera);
  j["tool"] = markerJson(f.tool);
  for (const auto& n : f.notes) j["notes"].push_back(n);

  const auto t2 = std::chrono::steady_clock::now();
  std::string stroke = "none";
  bool touching = false;
  std::optional<core::GridPoint> control;
  if (f.tipValid) {
    ++s.framesWithTip;
    const Eigen::Vector3d p = f.tipPlanet * scale;
    j["tip_planet_m"] = vec(f.tipPlanet);
    j["tip_height_mm"] = std::round(f.tipHeight * 1e6) / 1e3;
    if (f.tipHeld) j["tip_held"] = true;
    touching = f.touching && p.allFinite() && p.norm() > 0;
    if (touching) {
      ++s.touchingFrames;
      const auto c = edit::nearestVertex(chart, p);
      control = c;
      j["control_vertex"] = {c.u, c.v};
      const edit::ToolInput input{toolPosition(p, c, !pipeline.inStroke()),
                                  std::max(0.0, time - lastTime_)};
      try {
        if (!pipeline.inStroke()) {
          const auto r = pipeline.beginStroke(tool, input);
          ++s.strokes;
          ++s.stamps;
          s.modifiedVertices += r.modifiedVertices;
          j["stamps"] = 1;
          j["modified_vertices"] = r.modifiedVertices;
          stroke = "begin";
        } else {
          const auto r = pipeline.moveTo(input);
          s.stamps += r.stamps;
          s.modifiedVertices += r.modifiedVertices;
          j["stamps"] = r.stamps;
          j["modified_vertices"] = r.modifiedVertices;
          stroke = "move";
        }
      } catch (const core::InputError& e) {
        ++s.skippedFrames;
        j["notes"].push_back(std::string("edit skipped: ") + e.what());
      }
    }
  }
  if (!touching && pipeline.inStroke()) {
    pipeline.endStroke();
    stroke = "end";
  }
  j["touching"] = touching;
  j["stroke"] = stroke;
  if (p_->settler && o.tool == ReplayTool::kDisplace) {
    const auto r = p_->settler->frame();
    s.settleCellSteps += r.cellSteps;
    s.settleFramesAtRest += r.atRest;
    if (r.steps > 0) j["settle_steps"] = r.steps;
    out.settled = r.dirty;
  }
  out.times.editMs = msSince(t2);
  lastTime_ = time;
  if (f.planet.usable()) {
    out.planetInCamera = p_->scene.planetFromMarker(f.planet.pose);
    if (rotated_) out.planetInCamera->R = out.planetInCamera->R * userRotation_;
    if (f.tool.usable()) {
      tracking::ToolShape shape = p_->toolShape;
      if (f.tipValid) shape.tip = f.tool.pose.inverse().apply(f.tipCamera);
      out.toolTriangles =
          tracking::toolTriangles(shape, out.planetInCamera->inverse() * f.tool.pose, scale);
    }
  }
  out.touching = touching;
  out.control = control;
  out.stroke = stroke;
  out.logLine = j.dump();
  ++s.frames;
  return out;
}

}  // namespace ps::replay
