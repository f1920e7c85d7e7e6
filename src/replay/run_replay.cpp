// runReplay: a video through the FrameStepper (replay.cpp) frame by frame, the recording's
// settings sidecar played alongside, and what the whole run says of the recording (a truncated
// file, markers never seen) in the summary's warnings.
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

#include "replay/replay.hpp"
#include "replay/session_timeline.hpp"

namespace ps::replay {

namespace {

// Names as the user gave them: "id 0" for a single marker, "the board's ids 10-18, ..."
std::string markerNames(const tracking::MarkerTrackerConfig& m) {
  if (!m.layout) return "id " + std::to_string(m.id);
  std::string ids;
  for (int id : m.layout->ids()) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
  return m.layout->source + ", ids " + ids;
}

// What the whole run says of the recording: cut short, or its markers never seen.
void warnAboutTheRecording(ReplaySummary& s, const tracking::FrameSource& source,
                           const FrameStepper& stepper, const ReplayOptions& o) {
  if (s.truncated)
    s.warnings.push_back(
        source.name() + ": the video ended at frame " + std::to_string(s.frames) + " of the " +
        std::to_string(s.announcedFrames) +
        " its container announced (truncated or corrupt); replayed what was there");
  if (!stepper.anyMarker())
    s.warnings.push_back(source.name() + ": no marker of " + stepper.family() + " (" +
                         markerNames(o.scene.planet) + "; " + markerNames(o.scene.tool) +
                         ") was ever seen; nothing was sculpted" +
                         (o.scene.planet.layout || o.scene.tool.layout
                              ? std::string(" (a recording made with the single planet and tool "
                                            "markers replays with --board single --tool-layout "
                                            "flat)")
                              : std::string()));
  else if (s.framesWithPlanet == 0)
    s.warnings.push_back(source.name() + ": the planet's markers (" + markerNames(o.scene.planet) +
                         ") were never seen");
  else if (s.framesWithTool == 0)
    s.warnings.push_back(source.name() + ": the tool's markers (" + markerNames(o.scene.tool) +
                         ") were never seen");
  if (s.skippedFrames > 0)
    s.warnings.push_back(std::to_string(s.skippedFrames) +
                         " frame(s) had their edit refused; the log's notes say why");
}

std::string timingLine(int frame, const StepTimes& t) {
  return nlohmann::json{{"frame", frame},
                        {"detect_ms", std::round(t.detectMs * 1000) / 1000},
                        {"track_ms", std::round(t.trackMs * 1000) / 1000},
                        {"edit_ms", std::round(t.editMs * 1000) / 1000}}
      .dump();
}

}  // namespace

ReplaySummary runReplay(tracking::FrameSource& source, const tracking::CameraCalibration& calibIn,
                        terrain::Terrain& planet, const ReplayOptions& options, std::ostream& log,
                        std::ostream* timings, const ProgressFn& progress, const FrameHook& hook,
                        const SessionTimeline* timeline) {
  ReplayOptions o = options;
  // The live session kept an undo journal; its undo lines need one here.
  if (timeline) o.undo = o.undo || timeline->hasUndoRedo();
  o.validate();
  const tracking::CameraCalibration calib = calibIn.forImageSize(source.size());
  FrameStepper stepper(calib, planet, o);
  std::optional<SettingsControl> control;
  std::optional<TimelinePlayer> player;
  if (timeline) {
    control.emplace(stepper);
    player.emplace(*timeline, *control);
  }
  const double fps = source.fps() > 0 ? source.fps() : o.fallbackFps;

  cv::Mat image;
  bool limited = false;
  while (true) {
    limited = o.maxFrames > 0 && stepper.summary().frames >= o.maxFrames;
    if (limited || !source.read(image)) break;
    // The sidecar counts recorded frames, as the live app wrote them.
    if (player) player->before(stepper.summary().frames);
    const int frame = source.index();
    // A live session's times (a camera's clock) when its sidecar has them.
    const double time = timeline ? timeline->timeOf(stepper.summary().frames) : frame / fps;
    const StepResult r = stepper.step(image, frame, time);
    if (hook) {
      const FrameContext ctx{frame,
                             time,
                             image,
                             r.scene,
                             calib,
                             planet,
                             stepper.scale(),
                             r.planetInCamera,
                             r.touching,
                             r.control,
                             stepper.toolRadius(),
                             stepper.viewPatch(),
                             r.toolTriangles};
      hook(ctx);
    }
    log << r.logLine << "\n";
    if (timings) *timings << timingLine(frame, r.times) << "\n";
    if (progress) progress(stepper.summary().frames, source.announcedFrames());
  }
  if (player && !limited) player->finish(stepper.summary().frames);
  stepper.endStroke();
  ReplaySummary s = stepper.summary();
  if (player) {
    s.sessionChanges = player->applied();
    s.warnings.insert(s.warnings.end(), player->warnings().begin(), player->warnings().end());
  }
  s.announcedFrames = source.announcedFrames();
  s.truncated = source.truncated();
  warnAboutTheRecording(s, source, stepper, o);
  return s;
}

}  // namespace ps::replay
