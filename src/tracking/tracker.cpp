#include "tracking/tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "tracking/body_pose.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/tool_shape.hpp"

namespace ps::tracking {

namespace {
// Rigid sets (boards, tool solids): a measurement more than 50 mm from the last pose (1.5 m/s
// at 30 frames a second) or turned more than 8 degrees from it (240 degrees/s) is a new shot,
// not motion (the sweep's cuts turn the board 10.4-40 degrees).
constexpr double kRigidSetRestartJump = 0.05;
constexpr double kRigidSetRestartTurn = 8.0 * M_PI / 180.0;
// A tool solid's hold ends once its tip would have drifted 5 mm at the speed it last had.
constexpr double kToolHoldMaxDrift = 0.005;

void checkPositive(double v, const std::string& what) {
  if (!(v > 0) || !std::isfinite(v))
    throw core::InputError(what + " = " + core::formatNumber(v, 6) + " is not > 0");
}
void checkParams(const OneEuroParams& p, const std::string& what) {
  checkPositive(p.minCutoff, what + " min cutoff (Hz)");
  checkPositive(p.dCutoff, what + " speed cutoff (Hz)");
  if (!(p.beta >= 0) || !std::isfinite(p.beta))
    throw core::InputError(what + " beta = " + core::formatNumber(p.beta, 6) + " is not >= 0");
}
Eigen::Vector2d centre(const std::array<cv::Point2d, 4>& c) {
  return {0.25 * (c[0].x + c[1].x + c[2].x + c[3].x), 0.25 * (c[0].y + c[1].y + c[2].y + c[3].y)};
}
}  // namespace

std::string toString(TrackState s) {
  constexpr core::NameTable<TrackState, 3> kNames{"track state",
                                                  {{{TrackState::kLost, "lost"},
                                                    {TrackState::kTracked, "tracked"},
                                                    {TrackState::kHeld, "held"}}}};
  return kNames.nameOf(s);
}

void MarkerTrackerConfig::validate() const {
  if (id < 0) throw core::InputError("marker id " + std::to_string(id) + " is negative");
  checkPositive(size, "marker " + std::to_string(id) + " size (m)");
  checkParams(translation, "translation filter");
  checkParams(rotation, "rotation filter");
  if (!(holdSeconds >= 0))
    throw core::InputError("hold = " + core::formatNumber(holdSeconds, 6) + " s is not >= 0");
  if (!(ambiguityRatio >= 1))
    throw core::InputError("ambiguity ratio = " + core::formatNumber(ambiguityRatio, 6) +
                           " is not >= 1");
  checkPositive(maxReprojectionPx, "max reprojection error (px)");
  for (const auto& [v, what] :
       {std::pair{restartJump, "filter restart jump (m)"},
        std::pair{restartTurn, "filter restart turn (rad)"},
        std::pair{holdMaxDrift, "hold max drift (m)"}, std::pair{driftRadius, "drift radius (m)"}})
    if (!(v >= 0) || !std::isfinite(v))
      throw core::InputError(std::string(what) + " = " + core::formatNumber(v, 6) + " is not >= 0");
  if (layout && layout->markers.empty())
    throw core::InputError(layout->source + ": the layout has no markers");
}

bool MarkerTrackerConfig::owns(int markerId) const {
  return layout ? layout->find(markerId) != nullptr : markerId == id;
}

bool MarkerTrackerConfig::owns(const Detection& d) const {
  const std::string& mine = familyName();
  if (!d.family.empty() && !mine.empty() && d.family != mine) return false;
  return owns(d.id);
}

std::string MarkerTrackerConfig::name() const {
  return layout ? "layout " + layout->source : "marker " + std::to_string(id);
}

void SceneConfig::useBoard(std::shared_ptr<const MarkerLayout> board) {
  planet.layout = std::move(board);
  planet.holdWhileStill = planet.layout != nullptr;
  planet.restartJump = planet.layout ? kRigidSetRestartJump : 0.0;
  planet.restartTurn = planet.layout ? kRigidSetRestartTurn : 0.0;
}

void SceneConfig::useToolLayout(std::shared_ptr<const MarkerLayout> layout) {
  tool.layout = std::move(layout);
  if (tool.layout && tool.layout->tip) tipOffset = *tool.layout->tip;
  tool.restartJump = tool.layout ? kRigidSetRestartJump : 0.0;
  tool.restartTurn = tool.layout ? kRigidSetRestartTurn : 0.0;
  tool.holdMaxDrift = tool.layout ? kToolHoldMaxDrift : 0.0;
  tool.driftRadius = tool.layout ? tipOffset.norm() : 0.0;
}

MarkerTracker::MarkerTracker(MarkerTrackerConfig config)
    : config_(config), tFilter_(config.translation), rFilter_(config.rotation) {
  config_.validate();
}

void MarkerTracker::reset() {
  tFilter_.reset();
  rFilter_.reset();
  have_ = false;
  measuredLast_ = false;
  speed_ = -1;
}

bool MarkerTracker::measure(std::span<const Detection> detections, const CameraCalibration& calib,
                            MarkerEstimate& e) const {
  const Detection* use = nullptr;
  if (detections.size() == 1) {
    use = &detections[0];
  } else if (detections.size() > 1) {
    if (have_) {
      // The one nearest where the marker was.
      const auto expected = projectMarker(last_, config_.size, calib);
      double best = std::numeric_limits<double>::infinity();
      for (const auto& d : detections) {
        const double dist = (centre(d.corners) - centre(expected)).norm();
        if (dist < best) best = dist, use = &d;
      }
      e.note = "id " + std::to_string(config_.id) + " seen " + std::to_string(detections.size()) +
               " times; used the one nearest its last pose";
    } else {
      e.note = "id " + std::to_string(config_.id) + " seen " + std::to_string(detections.size()) +
               " times and no last pose to tell them apart; none used";
    }
  }
  if (!use) return false;
  const auto cands = solveMarkerPose(use->corners, config_.size, calib);
  const auto choice = choosePose(cands, have_ ? &last_ : nullptr, config_.ambiguityRatio);
  if (!choice.valid) {
    e.note = "id " + std::to_string(config_.id) + ": the pose solver gave no finite pose";
    return false;
  }
  if (cands.rms[std::size_t(choice.candidate)] > config_.maxReprojectionPx) {
    e.note = "id " + std::to_string(config_.id) + ": reprojection error " +
             core::formatNumber(cands.rms[std::size_t(choice.candidate)], 6) + " px > " +
             core::formatNumber(config_.maxReprojectionPx, 6) + " px; not used";
    return false;
  }
  e.raw = choice.pose;
  e.corners = use->corners;
  e.rms = cands.rms[std::size_t(choice.candidate)];
  e.ratio = choice.ratio;
  e.candidate = choice.candidate;
  e.byContinuity = choice.byContinuity;
  e.ids = {config_.id};
  return true;
}

bool MarkerTracker::measureBody(std::span<const Detection> detections,
                                const CameraCalibration& calib, MarkerEstimate& e) const {
  const BodyPoseResult r = solveBodyPose(*config_.layout, detections, calib,
                                         have_ ? &last_ : nullptr, config_.ambiguityRatio);
  e.note = r.note;
  if (!r.valid) return false;
  if (r.rms > config_.maxReprojectionPx) {
    e.note += (e.note.empty() ? "" : "; ") + config_.name() + ": reprojection error " +
              core::formatNumber(r.rms, 6) + " px > " +
              core::formatNumber(config_.maxReprojectionPx, 6) + " px; not used";
    return false;
  }
  e.raw = r.pose;
  e.rms = r.rms;
  e.ratio = r.ratio;
  e.byContinuity = r.byContinuity;
  e.ids = r.ids;
  return true;
}

bool MarkerTracker::agrees(const Detection& d, const CameraCalibration& calib, double maxTurn,
                           double maxShift) const {
  if (!have_ || config_.layout) return false;
  const auto cands = solveMarkerPose(d.corners, config_.size, calib);
  const auto choice = choosePose(cands, &last_, config_.ambiguityRatio);
  return choice.valid && rotationAngle(choice.pose.R, last_.R) <= maxTurn &&
         (choice.pose.t - last_.t).norm() <= maxShift;
}

MarkerEstimate MarkerTracker::update(std::span<const Detection> detections,
                                     const CameraCalibration& calib, double time,
                                     bool cameraStill) {
  BoardHint hint;
  hint.cameraStill = cameraStill;
  return update(detections, calib, time, hint);
}

MarkerEstimate MarkerTracker::update(std::span<const Detection> detections,
                                     const CameraCalibration& calib, double time,
                                     const BoardHint& hint) {
  const bool cameraStill = hint.cameraStill;
  MarkerEstimate e;
  e.id = config_.id;
  const double dt = have_ ? time - lastTime_ : 0.0;
  lastTime_ = time;
  e.measured = config_.layout ? measureBody(detections, calib, e) : measure(detections, calib, e);
  if (e.measured) {
    // Filters restart after a loss (a held pose is no base to filter from), and on a jump.
    e.restarted =
        have_ &&
        ((config_.restartJump > 0 && (e.raw.t - last_.t).norm() > config_.restartJump) ||
         (config_.restartTurn > 0 && rotationAngle(e.raw.R, last_.R) > config_.restartTurn));
    const bool restart = !have_ || e.restarted;
    const double fdt = restart ? 0.0 : dt;
    if (restart) {
      tFilter_.reset();
      rFilter_.reset();
    }
    Pose p = e.raw;
    if (config_.filter) {
      p.t = tFilter_.filter(e.raw.t, fdt);
      p.R = rFilter_.filter(Eigen::Quaterniond(e.raw.R), fdt).toRotationMatrix();
    }
    if (config_.holdMaxDrift > 0)
      speed_ =
          have_ && measuredLast_ && dt > 0
              ? ((p.t - last_.t).norm() + rotationAngle(p.R, last_.R) * config_.driftRadius) / dt
              : -1;
    e.pose = p;
    e.state = TrackState::kTracked;
    last_ = p;
    have_ = true;
    measuredLast_ = true;
    lastSeen_ = lastStill_ = time;
    return e;
  }
  measuredLast_ = false;
  if (have_ && config_.holdWhileStill && hint.carried) {
    // The plane around the board carries it: filtered on from the last pose, as a measurement.
    const Pose& c = *hint.carried;
    const bool restart =
        (config_.restartJump > 0 && (c.t - last_.t).norm() > config_.restartJump) ||
        (config_.restartTurn > 0 && rotationAngle(c.R, last_.R) > config_.restartTurn);
    if (restart) {
      tFilter_.reset();
      rFilter_.reset();
    }
    Pose p = c;
    if (config_.filter) {
      p.t = tFilter_.filter(c.t, restart ? 0.0 : dt);
      p.R = rFilter_.filter(Eigen::Quaterniond(c.R), restart ? 0.0 : dt).toRotationMatrix();
    }
    last_ = p;
    lastStill_ = time;
    e.pose = p;
    e.state = TrackState::kHeld;
    e.carried = true;
    e.sinceSeen = time - lastSeen_;
    return e;
  }
  if (have_ && config_.holdWhileStill && hint.cameraMoved) {
    // Known stale: not drawn at all.
    reset();
    e.state = TrackState::kLost;
    return e;
  }
  if (have_ && config_.holdWhileStill && cameraStill) {
    lastStill_ = time;
    e.heldStill = true;
  }
  // The short hold counts from the last frame seen, or judged still; it ends early once the
  // pose would have drifted too far at its last speed.
  const bool drifted =
      config_.holdMaxDrift > 0 && speed_ >= 0 && speed_ * (time - lastSeen_) > config_.holdMaxDrift;
  if (have_ && !drifted &&
      (e.heldStill || time - std::max(lastSeen_, lastStill_) <= config_.holdSeconds + 1e-9)) {
    e.state = TrackState::kHeld;
    e.pose = last_;
    e.sinceSeen = time - lastSeen_;
    return e;
  }
  if (have_) reset();
  e.state = TrackState::kLost;
  return e;
}

void SceneConfig::validate() const {
  planet.validate();
  tool.validate();
  if (!planet.layout && !tool.layout && planet.id == tool.id)
    throw core::InputError("the planet and tool markers have the same id " +
                           std::to_string(planet.id));
  // Ids clash within one family only (a board and a tool of two families may share ids); an
  // unnamed family may be either.
  const std::string &planetFamily = planet.familyName(), &toolFamily = tool.familyName();
  const bool oneFamily = planetFamily.empty() || toolFamily.empty() || planetFamily == toolFamily;
  const std::vector<int> toolIds = tool.layout ? tool.layout->ids() : std::vector<int>{tool.id};
  for (int id : toolIds)
    if (oneFamily && planet.layout && planet.owns(id))
      throw core::InputError(planet.name() + " and " + tool.name() + " both hold id " +
                             std::to_string(id));
  if (planet.layout && !planet.layout->planetCentre)
    throw core::InputError(planet.layout->source + ": a planet board needs \"planet_centre\"");
  if (tool.layout && !tool.layout->tip)
    throw core::InputError(tool.layout->source + ": a tool layout needs \"tip\"");
  checkPositive(planetRadius, "planet radius (m)");
  checkParams(tipFilter, "tip filter");
  if (!tipOffset.allFinite()) throw core::InputError("tool tip offset is not finite");
  if (!(touchDistance >= 0) || !std::isfinite(touchDistance))
    throw core::InputError("touch distance = " + core::formatNumber(touchDistance, 6) +
                           " m is not >= 0");
  if (!(toolCoverBandCells >= 0) || !std::isfinite(toolCoverBandCells))
    throw core::InputError("tool cover band = " + core::formatNumber(toolCoverBandCells, 6) +
                           " cells is not >= 0");
  checkPositive(coveredMaxTurn, "covered marker's max turn (rad)");
  checkPositive(coveredMaxShift, "covered marker's max shift (m)");
}

SceneTracker::SceneTracker(SceneConfig config)
    : config_(config), planet_(config.planet), tool_(config.tool), tipFilter_(config.tipFilter) {
  config_.validate();
  if (!config_.planet.layout && config_.toolCoverBandCells > 0)
    toolShape_ = std::make_shared<const ToolShape>(toolShape(
        config_, config_.tool.family.empty() ? std::string("tag36h11") : config_.tool.family));
}

void SceneTracker::reset() {
  planet_.reset();
  tool_.reset();
  tipFilter_.reset();
  tipHave_ = false;
}

void SceneTracker::setPlanetRadius(double metres) {
  SceneConfig c = config_;
  c.planetRadius = metres;
  c.validate();
  config_ = c;
}

Pose SceneTracker::planetFromMarker(const Pose& marker) const {
  Pose offset;
  if (config_.planet.layout) {
    // The planet rests on the board: its centre moves along the board's normal with its radius.
    const Eigen::Vector3d c = *config_.planet.layout->planetCentre;
    offset.t = c + Eigen::Vector3d(0, 0, config_.planetRadius - c.z());
  } else {
    offset.t = Eigen::Vector3d(0, 0, config_.planetRadius);
  }
  return marker * offset;
}

SceneFrame SceneTracker::update(const std::vector<Detection>& detections,
                                const CameraCalibration& calib, int frame, double time,
                                bool cameraStill) {
  BoardHint hint;
  hint.cameraStill = cameraStill;
  return update(detections, calib, frame, time, hint);
}

std::string SceneTracker::dropCoveredPlanet(const MarkerEstimate& tool,
                                            const CameraCalibration& calib,
                                            std::vector<Detection>& planet) const {
  // A pose that stays with the planet's is used: the covered corners dragged it too little to
  // matter (a tool sculpting over the marker covers its outline most of the time).
  if (!toolShape_ || !tool.usable() || planet.empty()) return "";
  const Pose& toolPose = tool.measured ? tool.raw : tool.pose;
  const std::string& family = config_.planet.familyName();
  std::string note;
  std::erase_if(planet, [&](const Detection& d) {
    const std::string f = !d.family.empty() ? d.family : !family.empty() ? family : "tag36h11";
    if (!toolCoversMarkerOutline(*toolShape_, toolPose, calib, d.corners, familyInfo(f).edgeCells,
                                 config_.toolCoverBandCells) ||
        planet_.agrees(d, calib, config_.coveredMaxTurn, config_.coveredMaxShift))
      return false;
    note = "id " + std::to_string(d.id) +
           ": the tool covers its outline and its pose jumps from the planet's; not used";
    return true;
  });
  return note;
}

SceneFrame SceneTracker::update(const std::vector<Detection>& detections,
                                const CameraCalibration& calib, int frame, double time,
                                const BoardHint& hint) {
  SceneFrame f;
  f.frame = frame;
  f.time = time;
  std::vector<Detection> p, t;
  std::vector<int> others;
  for (const auto& d : detections) {
    if (config_.planet.owns(d))
      p.push_back(d);
    else if (config_.tool.owns(d))
      t.push_back(d);
    else if (std::find(others.begin(), others.end(), d.id) == others.end())
      others.push_back(d.id);
  }
  // The tool first: where it stands decides whether the planet marker is seen whole.
  f.tool = tool_.update(t, calib, time);
  const std::string covered = dropCoveredPlanet(f.tool, calib, p);
  f.planet = planet_.update(p, calib, time, hint);
  if (!covered.empty())
    f.planet.note = covered + (f.planet.note.empty() ? "" : "; ") + f.planet.note;
  if (!f.planet.note.empty()) f.notes.push_back(f.planet.note);
  if (!f.tool.note.empty()) f.notes.push_back(f.tool.note);
  for (int id : others)
    f.notes.push_back("id " + std::to_string(id) + " is neither planet nor tool");
  if (f.tool.measured && config_.filterTip) {
    const Eigen::Vector3d tip = tipFromMarker(f.tool.raw);
    // The tip's filter restarts with the tool's (a jump) and when the tip alone jumps.
    if (tipHave_ && config_.tool.restartJump > 0 &&
        (f.tool.restarted || (tip - tipFilter_.value()).norm() > config_.tool.restartJump))
      tipFilter_.reset();
    const double dt = tipHave_ ? time - lastTipTime_ : 0.0;
    tipFilter_.filter(tip, dt);
    tipHave_ = true;
    lastTipTime_ = time;
  } else if (!f.tool.usable()) {
    tipFilter_.reset();
    tipHave_ = false;
  }
  if (f.planet.usable()) {
    f.planetCentreValid = true;
    f.planetCentreCamera = planetFromMarker(f.planet.pose).t;
  }
  if (f.planet.usable() && f.tool.usable()) {
    f.tipValid = true;
    f.tipHeld = !f.tool.measured;
    f.tipCamera = config_.filterTip && tipHave_ ? tipFilter_.value() : tipFromMarker(f.tool.pose);
    f.tipPlanet = planetFromMarker(f.planet.pose).inverse().apply(f.tipCamera);
    if (heightAbove_) {
      f.tipHeight = heightAbove_(f.tipPlanet);
    } else {
      const double surface = surface_ ? surface_(f.tipPlanet) : config_.planetRadius;
      f.tipHeight = f.tipPlanet.norm() - surface;
    }
    f.touching = f.tipHeight <= config_.touchDistance;
  }
  return f;
}

}  // namespace ps::tracking
