#pragma once
// Replay: a recorded (or synthetic) video through the whole pipeline with no window.
//   frame -> markers (tracking::Detector) -> planet and tool poses, tool tip in the planet's
//   frame (tracking::SceneTracker) -> scaled to the planet (metres) -> control vertex -> the edit
//   pipeline: while the tip touches the surface a stroke of the Gaussian brush follows it.
// The per-frame log (JSON lines) holds only what the input determines, so two replays of the
// same video, calibration and settings write identical logs and planets, bit for bit; times
// go to a separate stream.
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "core/grid.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "sand/settler.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/terrain.hpp"
#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/tool_shape.hpp"
#include "tracking/tracker.hpp"
#include "tracking/video.hpp"

namespace ps::replay {

// What the tool tip does while it touches the surface.
//   brush:    the Gaussian brush (edit/brush.hpp) at the tip's control vertex;
//   displace: the sand core's displacement tool (sand/displacement.hpp), a sphere pressed
//             `pressDepth` metres into the surface under the tip (its lowest point that far
//             below the surface at the control vertex); the displaced sand then settles
//             (thermal erosion to the material's talus angle) a budget of cell-steps per frame;
//   tin-sand: sand on a TIN (sand/tin_sand_tool.hpp, paper 000) with the displacement's radius,
//             spacing, material and press depth: each stamp presses a disc into a TIN of the
//             region, erodes it there and writes it back to the grid (no grid settling).
// The tip's measured depth is not used as the press depth: a millimetre of marker jitter is
// about 100 km on the planet.
enum class ReplayTool { kBrush, kDisplace, kTinSand };
std::string toString(ReplayTool t);
ReplayTool replayToolFromString(const std::string& s);  // throws core::InputError

struct ReplayOptions {
  tracking::DetectorConfig detector;  // ids are set from the scene's planet and tool ids
  tracking::SceneConfig scene;
  ReplayTool tool = ReplayTool::kBrush;
  edit::BrushSettings brush = defaultBrush();
  sand::DisplacementSettings displace = defaultDisplacement();
  double pressDepth = 8000;  // m (displace)
  bool settle = true;        // displace: settle the sand every frame
  sand::SettleSettings settling;
  double fallbackFps = 30;  // when the video does not say
  int maxFrames = 0;        // 0: all
  bool undo = false;        // keep an undo journal (slower; off for replays)

  static edit::BrushSettings defaultBrush();
  static sand::DisplacementSettings defaultDisplacement();
  void validate() const;  // InputError naming the setting
};

struct ReplaySummary {
  int frames = 0;
  int framesWithPlanet = 0, framesWithTool = 0, framesWithTip = 0, touchingFrames = 0;
  // Of framesWithPlanet, those whose pose was held (no planet marker read this frame).
  int framesPlanetHeld = 0;
  int strokes = 0, stamps = 0;
  std::size_t modifiedVertices = 0;
  int skippedFrames = 0;            // frames whose edit was refused (see the log's notes)
  std::size_t settleCellSteps = 0;  // displace: sand settling work
  int settleFramesAtRest = 0;
  bool truncated = false;  // the video ended before its announced length
  int announcedFrames = -1;
  int sessionChanges = 0;             // sidecar lines applied (changes, undos, redos)
  std::vector<std::string> warnings;  // no marker ever seen, truncated video, ...
};

using ProgressFn = std::function<void(int frame, int total)>;

// What a frame hook sees after a frame's tracking and edit (to render AR frames, drive haptics,
// record): valid only during the call.
struct FrameContext {
  int frame = 0;
  double time = 0;
  const cv::Mat& image;
  const tracking::SceneFrame& scene;
  const tracking::CameraCalibration& calibration;  // for the video's size
  const terrain::Terrain& planet;
  double scale = 1;  // planet metres per metre of the marker world
  // The planet frame's pose in the camera frame (marker-world metres) while the planet marker
  // is tracked or held.
  std::optional<tracking::Pose> planetInCamera;
  bool touching = false;
  std::optional<core::GridPoint> control;  // the control vertex while touching
  double toolRadius = 0;                   // r_d of the active tool (m on the planet)
  // The sand TIN's region to draw at its own detail in place of the 4-8 mesh there
  // (FrameStepper::viewPatch); null: the grid's mesh alone.
  std::shared_ptr<const terrain::MeshPatch> patch;
  // The tracked tool's shape (StepResult::toolTriangles): what hides the planet.
  std::span<const Eigen::Vector3d> toolTriangles = {};
};
using FrameHook = std::function<void(const FrameContext&)>;

// One frame of the pipeline, shared by runReplay and the live app (app/cmd_live.cpp):
// detections -> scene -> control vertex -> the active tool through the edit pipeline (+ sand
// settling). Owns the detector, the scene tracker, the edit pipeline and the tools; counts into
// a ReplaySummary. The tool and its settings may change between frames (live panel): a change
// ends the open stroke first (a stroke keeps a pointer to its tool).
struct StepTimes {
  double detectMs = 0, trackMs = 0, editMs = 0;
};
struct StepResult {
  tracking::SceneFrame scene;
  std::optional<tracking::Pose> planetInCamera;  // planet frame in the camera frame, if usable
  bool touching = false;
  std::optional<core::GridPoint> control;
  std::string stroke = "none";  // none, begin, move, end
  // Heights sand settling changed this frame, outside the undo journal (displace tool); the
  // live app journals them (session/session_store.hpp).
  terrain::VertexBox settled;
  std::string logLine;  // the replay log's JSON line for this frame (no newline)
  StepTimes times;
  // The tool's solid and stick (tracking/tool_shape.hpp) as triangles in the planet frame
  // (planet metres, 3 points each) while both the planet and the tool have a pose; its stick
  // ends at the tracked tip. What the AR view draws in front of the planet
  // (render::PlanetRenderer::renderAR's occluders).
  std::vector<Eigen::Vector3d> toolTriangles;
};

class FrameStepper {
 public:
  // `calib` must already be for the frames' size (CameraCalibration::forImageSize). Throws
  // core::InputError for unusable settings or a planet without a radius.
  FrameStepper(const tracking::CameraCalibration& calib, terrain::Terrain& planet,
               const ReplayOptions& options);
  ~FrameStepper();
  FrameStepper(const FrameStepper&) = delete;
  FrameStepper& operator=(const FrameStepper&) = delete;

  // One frame: `frame` is the source's index, `time` its time (s).
  StepResult step(const cv::Mat& image, int frame, double time);
  // Ends an open stroke (one undo step).
  void endStroke();

  // Live changes (each ends an open stroke; InputError for bad settings, nothing changed).
  void setTool(ReplayTool tool);
  void setBrush(const edit::BrushSettings& brush);
  void setDisplacement(const sand::DisplacementSettings& displace, double pressDepth);
  // The planet turned by hand on its marker (live app: keys and mouse): planet-frame points are
  // `rotation` (planet from turned planet) applied to the turned planet's coordinates. The AR
  // pose, the tip and the surface under it all follow, so the tool sculpts where the turned
  // planet is drawn. Identity (the default) leaves everything bit-identical to a replay.
  void setUserRotation(const Eigen::Matrix3d& rotation);
  // The planet scaled by hand on its marker: its displayed radius in marker-world metres (the
  // scene's planetRadius). The planet's own metres do not change; scale() does, so the same
  // tool motion covers more or less of the planet. Ends an open stroke; InputError unless the
  // radius is finite and > 0 (nothing changed then).
  void setPlanetSize(double planetRadiusM);
  const Eigen::Matrix3d& userRotation() const { return userRotation_; }

  const ReplayOptions& options() const { return o_; }
  edit::EditPipeline& pipeline();
  const tracking::CameraCalibration& calibration() const { return calib_; }
  double scale() const { return scale_; }  // planet metres per marker-world metre
  double toolRadius() const;               // r_d of the active tool (m on the planet)
  // The TIN sand tool's region TIN as a patch for the view (terrain/mesh_patch), while it is
  // the planet's surface there: from the stroke's first stamp, through the stroke and after it,
  // until the grid no longer holds what the region wrote (an undo, another tool, settling, a
  // loaded planet; a redo back to it shows it again), a new stroke makes a new region, or the
  // tool or its settings change (the tool is made afresh). Null otherwise, and for other
  // tools. Made again only after a stamp or a change of the planet.
  std::shared_ptr<const terrain::MeshPatch> viewPatch();
  const ReplaySummary& summary() const { return s_; }
  bool anyMarker() const { return anyMarker_; }
  const std::string& family() const { return family_; }

 private:
  struct Parts;
  void rebuildTools();
  ReplayOptions o_;
  tracking::CameraCalibration calib_;
  terrain::Terrain& planet_;
  double scale_ = 1;
  std::unique_ptr<Parts> p_;
  ReplaySummary s_;
  bool anyMarker_ = false;
  double lastTime_ = 0;
  double strokeAltitude_ = 0;
  std::string family_;
  Eigen::Matrix3d userRotation_ = Eigen::Matrix3d::Identity();
  bool rotated_ = false;
};

struct SessionTimeline;  // replay/session_timeline.hpp

// Replays `source` onto `planet`. Writes one JSON line per frame to `log` and, if given, one
// line of times per frame to `timings`. With a live session's `timeline` (its sidecar), its
// settings and each change, undo and redo are applied at their recorded frames (the options'
// tool settings are replaced by the timeline's). Throws core::InputError for unusable settings
// or a calibration for another aspect ratio; problems within frames are logged and skipped.
ReplaySummary runReplay(tracking::FrameSource& source, const tracking::CameraCalibration& calib,
                        terrain::Terrain& planet, const ReplayOptions& options, std::ostream& log,
                        std::ostream* timings = nullptr, const ProgressFn& progress = {},
                        const FrameHook& hook = {}, const SessionTimeline* timeline = nullptr);

}  // namespace ps::replay
