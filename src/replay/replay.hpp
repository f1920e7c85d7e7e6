#pragma once
// Replay: a recorded (or synthetic) video through the whole pipeline with no window.
//   frame -> markers (tracking::Detector) -> planet and tool poses, tool tip in the planet's
//   frame (tracking::SceneTracker) -> scaled to the planet (metres) -> control vertex -> the edit
//   pipeline: while the tip touches the surface a stroke of the Gaussian brush follows it.
// The per-frame log (JSON lines) holds only what the input determines, so two replays of the
// same video, calibration and settings write identical logs and planets, bit for bit; times
// go to a separate stream.
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "core/grid.hpp"
#include "edit/brush.hpp"
#include "sand/displacement.hpp"
#include "sand/settler.hpp"
#include "terrain/terrain.hpp"
#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/tracker.hpp"
#include "tracking/video.hpp"

namespace ps::replay {

// What the tool tip does while it touches the surface.
//   brush:    the Gaussian brush (edit/brush.hpp) at the tip's control vertex;
//   displace: the sand core's displacement tool (sand/displacement.hpp), a sphere pressed
//             `pressDepth` metres into the surface under the tip (its lowest point that far
//             below the surface at the control vertex); the displaced sand then settles
//             (thermal erosion to the material's talus angle) a budget of cell-steps per frame.
// The tip's measured depth is not used as the press depth: a millimetre of marker jitter is
// about 100 km on the planet.
enum class ReplayTool { kBrush, kDisplace };
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
  int strokes = 0, stamps = 0;
  std::size_t modifiedVertices = 0;
  int skippedFrames = 0;            // frames whose edit was refused (see the log's notes)
  std::size_t settleCellSteps = 0;  // displace: sand settling work
  int settleFramesAtRest = 0;
  bool truncated = false;  // the video ended before its announced length
  int announcedFrames = -1;
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
};
using FrameHook = std::function<void(const FrameContext&)>;

// Replays `source` onto `planet`. Writes one JSON line per frame to `log` and, if given, one
// line of times per frame to `timings`. Throws core::InputError for unusable settings or a
// calibration for another aspect ratio; problems within frames are logged and skipped.
ReplaySummary runReplay(tracking::FrameSource& source, const tracking::CameraCalibration& calib,
                        terrain::Terrain& planet, const ReplayOptions& options, std::ostream& log,
                        std::ostream* timings = nullptr, const ProgressFn& progress = {},
                        const FrameHook& hook = {});

}  // namespace ps::replay
