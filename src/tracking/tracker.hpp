#pragma once
// From detections to filtered marker poses, and from the planet and tool markers to the tool
// tip in the planet's frame.
//
// Per marker (MarkerTracker): the detection of its id -> IPPE candidates -> the candidate chosen
// by reprojection ratio, or by continuity with the last pose when the ratio is small -> One Euro
// filters on translation and rotation. A marker not seen holds its last pose for holdSeconds,
// then reports lost (and its filters start afresh when it comes back).
//
// A tracker may follow a rigid set of markers instead (marker_layout.hpp: the planet board, a
// tool solid): every visible marker of the set gives one joint pose (body_pose.hpp), filtered
// and held the same way; a board's pose is also held for as long as the camera is judged still
// (camera_motion.hpp), so a hand over the whole board does not make the planet vanish.
//
// The scene (SceneTracker): the planet sits on the planet marker, its centre planetRadius above
// the marker's centre along the marker's normal; the planet frame has the marker's axes (north
// pole along the normal). The tool tip is tipOffset in the tool marker's frame. The tip counts
// as touching when its height above the surface (SurfaceFn, a sphere by default) is at most
// touchDistance (inside the planet counts as touching too). A torus or a cylinder measures the
// tip's height with its own function (HeightFn); its displayed planetRadius is then its
// bounding sphere's radius, and that sphere stands on the board where a sphere planet would.
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/filter.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking {

enum class TrackState { kLost, kTracked, kHeld };
std::string toString(TrackState s);

struct MarkerTrackerConfig {
  int id = 0;
  double size = 0.05;  // edge of the black border (m)
  bool filter = true;
  OneEuroParams translation{2.0, 400.0, 1.0};  // speed in m/s
  OneEuroParams rotation{2.0, 8.0, 1.0};       // speed in rad/s
  double holdSeconds = 0.25;
  double ambiguityRatio = 4.0;     // below it, continuity decides between the two candidates
  double maxReprojectionPx = 4.0;  // a detection whose best candidate is worse is not used
  // A rigid set of markers tracked as one body (id and size are then unused); null: the single
  // marker `id` of edge `size`, on the classic path, unchanged bit for bit.
  std::shared_ptr<const MarkerLayout> layout;
  // While nothing is seen and the camera is judged still, hold the pose (boards); once the
  // camera moves, the usual hold of holdSeconds, then lost.
  bool holdWhileStill = false;
  // A measurement whose position is more than restartJump (m) from the last pose, or turned
  // more than restartTurn (rad) from it, restarts the filters (a cut in the video, a body
  // found again far from where it was held): a One Euro filter would otherwise leave a few
  // percent of the jump behind for a frame or two. 0: never (the single marker's classic path).
  double restartJump = 0;
  double restartTurn = 0;
  // The hold ends early once the pose, moving on at the speed it had when last seen, would have
  // drifted more than this (m) at `driftRadius` from the body's origin (a tool's tip): a tool
  // spun too fast to be read is not held where it was. The speed is that of the filtered pose
  // between the last two frames in a row that measured it (unknown: the plain hold). 0: hold
  // for holdSeconds.
  double holdMaxDrift = 0;
  double driftRadius = 0;
  static MarkerTrackerConfig single(int id, double size) {
    MarkerTrackerConfig c;
    c.id = id;
    c.size = size;
    return c;
  }
  // A single marker's family (a layout names its own); empty: whatever family is detected.
  std::string family;
  const std::string& familyName() const { return layout ? layout->family : family; }
  bool owns(int markerId) const;  // the id belongs to this tracker
  // The marker belongs to this tracker: its id, and its family when the detection names one
  // (ids are unique within a family only).
  bool owns(const Detection& d) const;
  std::string name() const;  // "marker 0", "board markers/planet-board.json"
  void validate() const;     // InputError
};

struct MarkerEstimate {
  int id = -1;
  TrackState state = TrackState::kLost;
  bool measured = false;  // a detection was used this frame
  Pose raw;               // the chosen candidate (when measured)
  Pose pose;              // filtered (tracked) or held; meaningless when lost
  std::array<cv::Point2d, 4> corners{};
  double rms = 0;    // reprojection RMS of the chosen candidate (px)
  double ratio = 0;  // second candidate's RMS / first's
  int candidate = 0;
  bool byContinuity = false;
  double sinceSeen = 0;    // seconds since the last measurement
  bool restarted = false;  // the filters restarted on a jump (restartJump, restartTurn)
  bool heldStill = false;  // held because the camera was judged still
  bool carried = false;    // carried by the plane around the board (BoardHint::carried)
  std::vector<int> ids;    // markers whose corners gave this frame's measurement
  std::string note;        // why a detection was not used, if one was not
  bool usable() const { return state != TrackState::kLost; }
};

// What a frame says of a board none of whose markers was read (the frame stepper's judge and
// plane tracker: camera_motion.hpp, plane_tracker.hpp). Read only with holdWhileStill.
struct BoardHint {
  bool cameraStill = false;  // the camera has not moved since the board was last measured
  // The camera was judged moved and nothing carries the board: its last pose is stale, and it
  // is lost at once (no short hold).
  bool cameraMoved = false;
  // The board's pose from the plane it lies on (the table around the hands): filtered as a
  // measurement is, reported held with `carried`.
  std::optional<Pose> carried;
};

class MarkerTracker {
 public:
  explicit MarkerTracker(MarkerTrackerConfig config);
  const MarkerTrackerConfig& config() const { return config_; }
  // `detections` are this frame's detections of the tracker's ids (a single marker: usually 0
  // or 1; with two, the one nearest the last pose is used, or none without a last pose).
  // `time` in seconds, increasing. `cameraStill`: the camera has not moved since the last
  // measurement (only read with holdWhileStill).
  MarkerEstimate update(std::span<const Detection> detections, const CameraCalibration& calib,
                        double time, bool cameraStill = false);
  MarkerEstimate update(std::span<const Detection> detections, const CameraCalibration& calib,
                        double time, const BoardHint& hint);
  // A single marker's detection would give a pose within maxTurn (rad) and maxShift (m) of the
  // pose it has now (tracked or held); false without one.
  bool agrees(const Detection& d, const CameraCalibration& calib, double maxTurn,
              double maxShift) const;
  void reset();

 private:
  bool measure(std::span<const Detection> detections, const CameraCalibration& calib,
               MarkerEstimate& e) const;
  bool measureBody(std::span<const Detection> detections, const CameraCalibration& calib,
                   MarkerEstimate& e) const;
  MarkerTrackerConfig config_;
  OneEuroVector tFilter_;
  OneEuroRotation rFilter_;
  bool have_ = false;  // a pose to hold or continue from
  Pose last_;
  double lastSeen_ = 0, lastTime_ = 0, lastStill_ = 0;
  bool measuredLast_ = false;  // the previous update measured the pose
  double speed_ = -1;          // drift speed (m/s) when last seen; < 0: unknown
};

struct SceneConfig {
  MarkerTrackerConfig planet = MarkerTrackerConfig::single(0, 0.08);
  MarkerTrackerConfig tool = MarkerTrackerConfig::single(1, 0.05);
  // The planet on a board: its markers tracked jointly and held while the camera is still; the
  // planet's centre at the board's planet_centre, moved along the board's normal when the
  // planet's radius differs from that height.
  void useBoard(std::shared_ptr<const MarkerLayout> board);
  // A tool solid: its markers tracked jointly, the tip at the layout's tip.
  void useToolLayout(std::shared_ptr<const MarkerLayout> tool);
  double planetRadius = 0.06;                  // m, the displayed planet
  Eigen::Vector3d tipOffset{0.0, -0.08, 0.0};  // tool tip in the tool marker's frame (m)
  double touchDistance = 0.004;                // m above the surface
  // The tip is computed from the tool's unfiltered pose and filtered as a point (camera frame):
  // the filter then acts on the quantity that matters, and rotation lag is not multiplied by
  // the stick's length.
  bool filterTip = true;
  OneEuroParams tipFilter{2.0, 400.0, 1.0};  // speed in m/s
  // A single planet marker whose outline the tool covers (its card or solid and stick, placed
  // by the tool's pose this frame, within this many of the marker's cells of an edge:
  // tool_shape.hpp, toolCoversMarkerOutline) is measured only when the pose it gives is within
  // coveredMaxTurn and coveredMaxShift of the planet's pose now; otherwise (or without a pose)
  // it is held as when not seen: its corners are dragged by what covers them, and the pose from
  // them can be its mirror image with a small reprojection error. 0: off.
  double toolCoverBandCells = 0.25;
  double coveredMaxTurn = 5.0 * M_PI / 180;  // rad
  double coveredMaxShift = 0.01;             // m
  void validate() const;                     // InputError naming the field
};

// Radius of the surface (m, the displayed planet's scale) under a point of the planet frame.
using SurfaceFn = std::function<double(const Eigen::Vector3d& pointInPlanetFrame)>;
// Height of a point of the planet frame above the surface (m, the displayed planet's scale;
// negative inside): for surfaces that are no sphere about the planet's centre (a torus, a
// cylinder), where a radius under the point says nothing.
using HeightFn = std::function<double(const Eigen::Vector3d& pointInPlanetFrame)>;

struct SceneFrame {
  int frame = 0;
  double time = 0;
  MarkerEstimate planet, tool;
  bool tipValid = false;           // both poses usable
  bool tipHeld = false;            // the tool marker is held, not seen this frame
  bool planetCentreValid = false;  // the planet has a pose
  Eigen::Vector3d planetCentreCamera = Eigen::Vector3d::Zero();  // camera frame (m)
  Eigen::Vector3d tipCamera = Eigen::Vector3d::Zero();
  Eigen::Vector3d tipPlanet = Eigen::Vector3d::Zero();  // planet frame (m)
  double tipHeight = 0;                                 // above the surface (m); negative inside
  bool touching = false;
  std::vector<std::string> notes;  // other ids seen, duplicates, rejected detections
};

struct ToolShape;

class SceneTracker {
 public:
  explicit SceneTracker(SceneConfig config);
  const SceneConfig& config() const { return config_; }
  void setSurface(SurfaceFn f) { surface_ = std::move(f); }
  // Measure the tip's height with `f` instead of |tip| - surface(tip) (which stays for spheres).
  void setHeightAbove(HeightFn f) { heightAbove_ = std::move(f); }
  // The displayed planet's radius (m) changed by hand: the planet frame moves along the marker's
  // normal with it; the filters keep their state. Throws core::InputError unless finite, > 0.
  void setPlanetRadius(double metres);
  // `cameraStill`: the camera has not moved since the planet was last measured (boards hold
  // their pose while it holds).
  SceneFrame update(const std::vector<Detection>& detections, const CameraCalibration& calib,
                    int frame, double time, bool cameraStill = false);
  SceneFrame update(const std::vector<Detection>& detections, const CameraCalibration& calib,
                    int frame, double time, const BoardHint& hint);
  // Camera-from-planet pose for a planet-marker pose.
  Pose planetFromMarker(const Pose& marker) const;
  // Tip in the camera frame for a tool-marker pose.
  Eigen::Vector3d tipFromMarker(const Pose& tool) const { return tool.apply(config_.tipOffset); }
  void reset();

 private:
  // Removes the single planet marker's detections whose outline the tool covers
  // (toolCoverBandCells); returns the note saying so, or "".
  std::string dropCoveredPlanet(const MarkerEstimate& tool, const CameraCalibration& calib,
                                std::vector<Detection>& planet) const;
  SceneConfig config_;
  MarkerTracker planet_, tool_;
  OneEuroVector tipFilter_;
  double lastTipTime_ = 0;
  bool tipHave_ = false;
  SurfaceFn surface_;
  HeightFn heightAbove_;
  std::shared_ptr<const ToolShape> toolShape_;  // for toolCoverBandCells
};

}  // namespace ps::tracking
