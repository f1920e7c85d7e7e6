#pragma once
// Replay: a recorded (or synthetic) video through the whole pipeline with no window.
//   frame -> markers (tracking::Detector) -> planet and tool poses, tool tip in the planet's
//   frame (tracking::SceneTracker) -> scaled to the planet (metres) -> control vertex -> the edit
//   pipeline: while the tip touches the surface a stroke of the Gaussian brush follows it.
// The per-frame log (JSON lines) holds only what the input determines, so two replays of the
// same video, calibration and settings write identical logs and planets, bit for bit; times
// go to a separate stream.
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "edit/brush.hpp"
#include "terrain/terrain.hpp"
#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/tracker.hpp"
#include "tracking/video.hpp"

namespace ps::replay {

struct ReplayOptions {
  tracking::DetectorConfig detector;  // ids are set from the scene's planet and tool ids
  tracking::SceneConfig scene;
  edit::BrushSettings brush = defaultBrush();
  double fallbackFps = 30;  // when the video does not say
  int maxFrames = 0;        // 0: all
  bool undo = false;        // keep an undo journal (slower; off for replays)

  static edit::BrushSettings defaultBrush();
  void validate() const;  // InputError naming the setting
};

struct ReplaySummary {
  int frames = 0;
  int framesWithPlanet = 0, framesWithTool = 0, framesWithTip = 0, touchingFrames = 0;
  int strokes = 0, stamps = 0;
  std::size_t modifiedVertices = 0;
  int skippedFrames = 0;   // frames whose edit was refused (see the log's notes)
  bool truncated = false;  // the video ended before its announced length
  int announcedFrames = -1;
  std::vector<std::string> warnings;  // no marker ever seen, truncated video, ...
};

using ProgressFn = std::function<void(int frame, int total)>;

// Replays `source` onto `planet`. Writes one JSON line per frame to `log` and, if given, one
// line of times per frame to `timings`. Throws core::InputError for unusable settings or a
// calibration for another aspect ratio; problems within frames are logged and skipped.
ReplaySummary runReplay(tracking::FrameSource& source, const tracking::CameraCalibration& calib,
                        terrain::Terrain& planet, const ReplayOptions& options, std::ostream& log,
                        std::ostream* timings = nullptr, const ProgressFn& progress = {});

}  // namespace ps::replay
