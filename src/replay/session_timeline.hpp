#pragma once
// A live session's settings timeline (docs/LIVE.md, "The session sidecar"): a recording's video
// carries only frames, so the settings the user changes while recording (tool, r_d, strength,
// raise/lower, planet size, the planet turned by hand, undo and redo) go to a JSON-lines sidecar
// next to it, and a replay applies them at the same recorded frames. Both sides change the
// stepper through one class, SettingsControl, so a replay cannot apply a change differently from
// the live app.
#include <Eigen/Core>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "replay/replay.hpp"

namespace ps::replay {

inline constexpr int kSessionTimelineVersion = 1;
// The sidecar header's "format".
inline constexpr const char* kSessionFormat = "planetsculpt-session";

// What changes what the tool does to the planet. (dist_max and the triangle budget change only
// the view, so they are not here.)
struct SessionSettings {
  ReplayTool tool = ReplayTool::kBrush;
  edit::BrushSettings brush = ReplayOptions::defaultBrush();
  sand::DisplacementSettings displace = ReplayOptions::defaultDisplacement();
  double pressDepth = 8000;
  double planetRadius = 0.06;  // the displayed planet's radius on its marker (m)
  double spinDeg = 0, tiltDeg = 0;

  static SessionSettings of(const ReplayOptions& o);  // not turned
  // The planet turned by hand: tilt about x after spin about z.
  Eigen::Matrix3d rotation() const;
  // InputError naming the first bad field.
  void validate() const;
  bool operator==(const SessionSettings&) const = default;
};
nlohmann::json toJson(const SessionSettings& s);
// The fields of `after` that differ from `before` (the sidecar's change lines).
nlohmann::json diff(const SessionSettings& before, const SessionSettings& after);

// Where the session started: enough to refuse a replay from another planet, calibration or marker
// set-up, and to make the start planet again when it was the default one.
struct SessionStart {
  std::string planetFile;  // "" : the default planet of (gridSide, seed)
  int gridSide = 0;
  std::uint64_t seed = 1;
  std::string chart = "latlong";       // the start planet's chart (sidecars before it: lat-long)
  bool chartNamed = false;             // the sidecar names it (false: one before charts)
  double radius = 0;                   // a sphere's; a torus's major radius, a cylinder's radius
  double minorRadius = 0, length = 0;  // a torus's tube radius, a cylinder's length; else 0
  std::uint32_t heightsCrc = 0;        // io::heightsChecksum of the heights at the first frame
  std::string calibrationFile;
  cv::Size imageSize;
  std::vector<double> K, distortion;  // the calibration scaled to the frames, as the stepper has it
  double fps = 30;  // the live input's: frame k's time is k / fps unless a time line says
  // Marker and tracker options (`replay`'s command line): the sidecar's win in a replay.
  std::string family;
  double decimate = 2;
  int planetId = 0, toolId = 1;
  double planetMarkerSize = 0.08, toolMarkerSize = 0.05, touchDistance = 0.004;
  Eigen::Vector3d tipOffset = Eigen::Vector3d::Zero();
  bool filter = true, settle = true;
  // The planet board and the tool solid the session tracked (null: the single markers), kept
  // whole in the sidecar so that the recording replays with them.
  std::shared_ptr<const tracking::MarkerLayout> board, toolLayout;
  std::size_t undoSteps = 0;  // strokes undoable at the start (made before the recording)

  // `calib` must be the one the stepper uses (scaled to the frames).
  static SessionStart of(const terrain::Terrain& planet, const std::string& planetFile,
                         int gridSide, std::uint64_t seed, const tracking::CameraCalibration& calib,
                         const std::string& calibrationFile, const ReplayOptions& o, double fps,
                         std::size_t undoSteps);
  // Copies the marker and tracker options into `o`.
  void applyTo(ReplayOptions& o) const;
};
// The sidecar header's "start" (the reader's parseStart reads it back).
nlohmann::json toJson(const SessionStart& s);

// Appends the sidecar while a recording runs: the header at open(), then one line per change
// and per undo or redo, each flushed at once so that a crash leaves every line before it.
class TimelineWriter {
 public:
  TimelineWriter() = default;
  ~TimelineWriter();
  TimelineWriter(const TimelineWriter&) = delete;
  TimelineWriter& operator=(const TimelineWriter&) = delete;

  // Creates (replaces) `path` with the header line. std::runtime_error naming the file.
  void open(const std::filesystem::path& path, const SessionStart& start,
            const SessionSettings& settings);
  void close();
  bool isOpen() const { return file_ != nullptr; }
  const std::filesystem::path& path() const { return path_; }
  // A frame went to the recording, stepped at `time` (s): later changes apply from the next one
  // on. A time other than frame / fps (a camera's clock, a recording started mid-video) gets a
  // line of its own, so that filters and rate brushes see the live times in a replay.
  void frameRecorded(double time);
  int frames() const { return frames_; }
  // Lines for what SettingsControl did; no-ops when closed. A write the disk refuses closes the
  // writer and sets error() (the frame loop goes on; the sidecar's lines so far stay readable).
  void change(const SessionSettings& before, const SessionSettings& after);
  void event(const std::string& what);
  const std::string& error() const { return error_; }

 private:
  void writeLine(const nlohmann::ordered_json& j);
  std::FILE* file_ = nullptr;
  std::filesystem::path path_;
  int frames_ = 0;
  double fps_ = 30;
  std::string error_;
};

// The one path from a settings change (the live panel, or a sidecar line) to the stepper.
class SettingsControl {
 public:
  explicit SettingsControl(FrameStepper& stepper);
  const SessionSettings& settings() const { return s_; }
  // Makes the stepper's settings `target`, in a fixed order (turn, size, brush, displacement,
  // tool; each ends an open stroke). A refused value throws core::InputError; what was applied
  // before it stays applied and is written to the sidecar.
  void apply(const SessionSettings& target);
  // End the open stroke and undo / redo one; InputError when there is nothing to undo / redo.
  void undo();
  void redo();
  // While recording: changes also go to `writer` (nullptr: not recording).
  void setWriter(TimelineWriter* writer) { writer_ = writer; }

 private:
  void applyParts(const SessionSettings& target);
  FrameStepper& stepper_;
  SessionSettings s_;
  TimelineWriter* writer_ = nullptr;
};

// A parsed sidecar.
struct TimelineEntry {
  int frame = 0;
  int line = 0;              // 1-based, for messages
  std::string event;         // "undo", "redo", or "" for a change
  SessionSettings settings;  // a change: every setting after it
};
struct SessionTimeline {
  std::filesystem::path path;
  SessionStart start;
  SessionSettings settings;  // at the first recorded frame
  std::vector<TimelineEntry> entries;
  std::vector<std::pair<int, double>> times;  // (frame, time s) where not frame / fps
  std::string warning;  // a torn last line (a crash while it was written), ignored
  bool hasUndoRedo() const;
  // The time recorded frame `frame` was stepped at in the live session.
  double timeOf(int frame) const;
};

// `VIDEO.session.jsonl`: where the live app writes the sidecar of a recording, and where a
// replay looks for it.
std::filesystem::path sessionSidecarPath(const std::filesystem::path& video);

// Throws core::InputError "FILE:LINE: what is wrong" (or "FILE: ..." for the whole file).
SessionTimeline readSessionTimeline(const std::filesystem::path& path);
// The same for a sidecar's text (`path` names it in messages).
SessionTimeline parseSessionTimeline(const std::string& text, const std::filesystem::path& path);

// InputError naming the sidecar when `planet` or `calib` (scaled to the frames) is not what the
// session started with.
void checkSessionStart(const SessionTimeline& t, const terrain::Terrain& planet,
                       const tracking::CameraCalibration& calib);

// Applies a timeline's lines to a replay: before(frame) those of that recorded frame, finish()
// those after the last one (changes made once the video had ended). Refused undo or redo lines
// (a stroke made before the recording started) become warnings.
class TimelinePlayer {
 public:
  TimelinePlayer(const SessionTimeline& t, SettingsControl& control);
  void before(int frame);
  void finish(int frames);
  int applied() const { return applied_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  void run(const TimelineEntry& e);
  const SessionTimeline& t_;
  SettingsControl& control_;
  std::size_t next_ = 0;
  int applied_ = 0;
  std::vector<std::string> warnings_;
};

}  // namespace ps::replay
