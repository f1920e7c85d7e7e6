#include "replay/session_timeline.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "core/grid.hpp"
#include "core/input_error.hpp"
#include "io/stroke_journal.hpp"
#include "tracking/marker_layout.hpp"

namespace ps::replay {

namespace {

constexpr const char* kFormat = "planetsculpt-session";

// One settings field of a line: how to read it into SessionSettings. Numbers are written with
// nlohmann's shortest round-trip form, so a double read back is the double written.
using FieldSetter = std::function<void(SessionSettings&, const nlohmann::json&)>;

double number(const nlohmann::json& v) {
  if (!v.is_number()) throw core::InputError("is not a number (" + v.dump() + ")");
  return v.get<double>();
}
bool boolean(const nlohmann::json& v) {
  if (!v.is_boolean()) throw core::InputError("is not true or false (" + v.dump() + ")");
  return v.get<bool>();
}
std::string text(const nlohmann::json& v) {
  if (!v.is_string()) throw core::InputError("is not a string (" + v.dump() + ")");
  return v.get<std::string>();
}

const std::map<std::string, FieldSetter>& fields() {
  static const std::map<std::string, FieldSetter> f = {
      {"tool", [](auto& s, auto& v) { s.tool = replayToolFromString(text(v)); }},
      {"brush_radius_m", [](auto& s, auto& v) { s.brush.radius = number(v); }},
      {"sigma", [](auto& s, auto& v) { s.brush.sigma = number(v); }},
      {"mu", [](auto& s, auto& v) { s.brush.mu = number(v); }},
      {"mode", [](auto& s, auto& v) { s.brush.mode = edit::brushModeFromString(text(v)); }},
      {"strength_m", [](auto& s, auto& v) { s.brush.strength = number(v); }},
      {"rate", [](auto& s, auto& v) { s.brush.rate = boolean(v); }},
      {"target_m", [](auto& s, auto& v) { s.brush.target = number(v); }},
      {"spacing", [](auto& s, auto& v) { s.brush.spacing = number(v); }},
      {"displace_radius_m", [](auto& s, auto& v) { s.displace.radius = number(v); }},
      {"rampart_width", [](auto& s, auto& v) { s.displace.rampartWidth = number(v); }},
      {"displace_spacing", [](auto& s, auto& v) { s.displace.spacing = number(v); }},
      {"press_m", [](auto& s, auto& v) { s.pressDepth = number(v); }},
      {"planet_radius_m", [](auto& s, auto& v) { s.planetRadius = number(v); }},
      {"spin_deg", [](auto& s, auto& v) { s.spinDeg = number(v); }},
      {"tilt_deg", [](auto& s, auto& v) { s.tiltDeg = number(v); }},
  };
  return f;
}

[[noreturn]] void fail(const std::filesystem::path& path, int line, const std::string& what) {
  throw core::InputError(path.string() + ":" + std::to_string(line) + ": " + what);
}

const nlohmann::json& member(const nlohmann::json& j, const char* key,
                             const std::filesystem::path& path, int line) {
  if (!j.is_object() || !j.contains(key)) fail(path, line, std::string("no \"") + key + "\"");
  return j.at(key);
}

template <class T>
T read(const nlohmann::json& j, const char* key, const std::filesystem::path& path, int line) {
  const nlohmann::json& v = member(j, key, path, line);
  const bool ok = std::is_same_v<T, bool>          ? v.is_boolean()
                  : std::is_same_v<T, std::string> ? v.is_string()
                  : std::is_integral_v<T>          ? v.is_number_integer()
                                                   : v.is_number();
  if (!ok) fail(path, line, std::string("\"") + key + "\" has the wrong type (" + v.dump() + ")");
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    const bool inRange = v.is_number_unsigned() ? std::in_range<T>(v.get<std::uint64_t>())
                                                : std::in_range<T>(v.get<std::int64_t>());
    if (!inRange)
      fail(path, line, std::string("\"") + key + "\" is out of range (" + v.dump() + ")");
  }
  return v.get<T>();
}

std::vector<double> numbers(const nlohmann::json& j, const char* key, std::size_t min,
                            std::size_t max, const std::filesystem::path& path, int line) {
  const nlohmann::json& v = member(j, key, path, line);
  std::vector<double> out;
  if (v.is_array())
    for (const auto& x : v) {
      if (!x.is_number()) break;
      out.push_back(x.get<double>());
    }
  if (!v.is_array() || out.size() != v.size() || out.size() < min || out.size() > max)
    fail(path, line,
         std::string("\"") + key + "\" is not a list of " + std::to_string(min) +
             (min == max ? "" : " to " + std::to_string(max)) + " numbers");
  return out;
}

// Applies a line's settings fields to `s`; every other key must be one of `allowed`.
void applyFields(const nlohmann::json& j, SessionSettings& s,
                 const std::vector<std::string>& allowed, const std::filesystem::path& path,
                 int line) {
  for (const auto& [key, value] : j.items()) {
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    const auto f = fields().find(key);
    if (f == fields().end()) fail(path, line, "unknown field \"" + key + "\"");
    try {
      f->second(s, value);
    } catch (const core::InputError& e) {
      fail(path, line, "\"" + key + "\" " + e.what());
    }
  }
}

SessionStart parseStart(const nlohmann::json& j, const std::filesystem::path& path, int line) {
  SessionStart s;
  const auto& planet = member(j, "planet", path, line);
  s.planetFile = read<std::string>(planet, "file", path, line);
  s.gridSide = read<int>(planet, "grid", path, line);
  try {
    core::GridSize::fromSide(s.gridSide);
  } catch (const core::InputError& e) {
    fail(path, line, std::string("\"grid\": ") + e.what());
  }
  s.seed = read<std::uint64_t>(planet, "seed", path, line);
  s.radius = read<double>(planet, "radius_m", path, line);
  s.heightsCrc = read<std::uint32_t>(planet, "heights_crc32", path, line);
  const auto& cal = member(j, "calibration", path, line);
  s.calibrationFile = read<std::string>(cal, "file", path, line);
  s.imageSize = {read<int>(cal, "width", path, line), read<int>(cal, "height", path, line)};
  s.K = numbers(cal, "K", 9, 9, path, line);
  s.distortion = numbers(cal, "distortion", 0, 14, path, line);
  s.fps = read<double>(j, "fps", path, line);
  const auto& m = member(j, "markers", path, line);
  s.family = read<std::string>(m, "family", path, line);
  s.decimate = read<double>(m, "decimate", path, line);
  s.planetId = read<int>(m, "planet_id", path, line);
  s.planetMarkerSize = read<double>(m, "planet_marker_m", path, line);
  s.toolId = read<int>(m, "tool_id", path, line);
  s.toolMarkerSize = read<double>(m, "tool_marker_m", path, line);
  const auto tip = numbers(m, "tip_m", 3, 3, path, line);
  s.tipOffset = {tip[0], tip[1], tip[2]};
  s.touchDistance = read<double>(m, "touch_m", path, line);
  s.filter = read<bool>(m, "filter", path, line);
  for (const auto& [key, layout] : {std::pair{"board", &s.board}, {"tool_layout", &s.toolLayout}})
    if (m.contains(key)) {
      try {
        *layout = std::make_shared<const tracking::MarkerLayout>(
            tracking::parseMarkerLayout(m[key], std::string("markers.") + key));
      } catch (const core::InputError& e) {
        fail(path, line, e.what());
      }
    }
  s.settle = read<bool>(j, "settle", path, line);
  s.undoSteps = read<std::size_t>(j, "undo_steps", path, line);
  if (!(s.fps > 0 && s.fps <= 1000))
    fail(path, line, "\"fps\" = " + std::to_string(s.fps) + " is not in (0, 1000]");
  try {
    ReplayOptions o;
    s.applyTo(o);
    o.validate();  // the marker and tracker options a replay takes from here
  } catch (const core::InputError& e) {
    fail(path, line, e.what());
  }
  return s;
}

nlohmann::json toJson(const SessionStart& s) {
  nlohmann::json j = {{"planet",
                       {{"file", s.planetFile},
                        {"grid", s.gridSide},
                        {"seed", s.seed},
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
  if (s.board) j["markers"]["board"] = tracking::toJson(*s.board);
  if (s.toolLayout) j["markers"]["tool_layout"] = tracking::toJson(*s.toolLayout);
  return j;
}

}  // namespace

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
  s.radius = planet.chart().radius();
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

TimelineWriter::~TimelineWriter() {
  close();
}

void TimelineWriter::open(const std::filesystem::path& path, const SessionStart& start,
                          const SessionSettings& settings) {
  close();
  file_ = std::fopen(path.c_str(), "w");
  if (!file_)
    throw std::runtime_error(path.string() + ": cannot write the session sidecar (" +
                             std::strerror(errno) + ")");
  path_ = path;
  frames_ = 0;
  fps_ = start.fps > 0 ? start.fps : 30;
  error_.clear();
  writeLine({{"format", kFormat},
             {"version", kSessionTimelineVersion},
             {"frame", 0},
             {"start", nlohmann::ordered_json(toJson(start))},
             {"settings", nlohmann::ordered_json(toJson(settings))}});
}

void TimelineWriter::close() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
}

void TimelineWriter::writeLine(const nlohmann::ordered_json& j) {
  if (!file_) return;
  const std::string line = j.dump() + "\n";
  // One write and a flush per line: a crash (not a power cut) leaves whole lines only, and at
  // most the last one torn; the reader ignores that one.
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0) {
    error_ = path_.string() + ": cannot write the session sidecar (" + std::strerror(errno) +
             "); stopped writing it";
    close();
  }
}

void TimelineWriter::frameRecorded(double time) {
  if (time != frames_ / fps_) writeLine({{"frame", frames_}, {"time_s", time}});
  ++frames_;
}

void TimelineWriter::change(const SessionSettings& before, const SessionSettings& after) {
  const nlohmann::json d = diff(before, after);
  if (d.empty()) return;
  nlohmann::ordered_json line = {{"frame", frames_}};  // the frame first, for people reading
  for (const auto& [key, value] : d.items()) line[key] = value;
  writeLine(line);
}

void TimelineWriter::event(const std::string& what) {
  writeLine({{"frame", frames_}, {"event", what}});
}

SessionControl::SessionControl(FrameStepper& stepper)
    : stepper_(stepper), s_(SessionSettings::of(stepper.options())) {}

void SessionControl::apply(const SessionSettings& t) {
  const SessionSettings before = s_;
  try {
    applyParts(t);
  } catch (...) {
    if (writer_) writer_->change(before, s_);  // the sidecar holds what the stepper has
    throw;
  }
  if (writer_) writer_->change(before, s_);
}

void SessionControl::applyParts(const SessionSettings& t) {
  if (t.spinDeg != s_.spinDeg || t.tiltDeg != s_.tiltDeg) {
    stepper_.setUserRotation(t.rotation());
    s_.spinDeg = t.spinDeg;
    s_.tiltDeg = t.tiltDeg;
  }
  if (t.planetRadius != s_.planetRadius) {
    stepper_.setPlanetSize(t.planetRadius);
    s_.planetRadius = t.planetRadius;
  }
  if (!(t.brush == s_.brush)) {
    stepper_.setBrush(t.brush);
    s_.brush = t.brush;
  }
  if (!(t.displace == s_.displace) || t.pressDepth != s_.pressDepth) {
    stepper_.setDisplacement(t.displace, t.pressDepth);
    s_.displace = t.displace;
    s_.pressDepth = t.pressDepth;
  }
  if (t.tool != s_.tool) {
    stepper_.setTool(t.tool);
    s_.tool = t.tool;
  }
}

void SessionControl::undo() {
  stepper_.endStroke();
  stepper_.pipeline().undo();
  if (writer_) writer_->event("undo");
}

void SessionControl::redo() {
  stepper_.endStroke();
  stepper_.pipeline().redo();
  if (writer_) writer_->event("redo");
}

bool SessionTimeline::hasUndoRedo() const {
  for (const auto& e : entries)
    if (!e.event.empty()) return true;
  return false;
}

double SessionTimeline::timeOf(int frame) const {
  const auto it = std::lower_bound(times.begin(), times.end(), std::pair<int, double>(frame, -1.0));
  if (it != times.end() && it->first == frame) return it->second;
  return frame / (start.fps > 0 ? start.fps : 30);
}

std::filesystem::path sessionSidecarPath(const std::filesystem::path& video) {
  return std::filesystem::path(video.string() + ".session.jsonl");
}

SessionTimeline readSessionTimeline(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(path.string() + ": cannot read the session sidecar");
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw core::InputError(path.string() + ": cannot read the session sidecar");
  return parseSessionTimeline(all, path);
}

SessionTimeline parseSessionTimeline(const std::string& all, const std::filesystem::path& path) {
  SessionTimeline t;
  t.path = path;
  std::size_t at = 0;
  int line = 0, lastFrame = 0;
  while (at < all.size()) {
    const std::size_t end = all.find('\n', at);
    const bool complete = end != std::string::npos;
    const std::string text = all.substr(at, complete ? end - at : std::string::npos);
    at = complete ? end + 1 : all.size();
    ++line;
    if (text.find_first_not_of(" \t\r") == std::string::npos) {
      if (complete) fail(path, line, "empty line");
      break;
    }
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object()) {
      // A crash while the last line was written leaves it torn: the lines before it stand.
      if (!complete && line > 1) {
        t.warning = path.string() + ":" + std::to_string(line) +
                    ": the last line is cut short (a crash while it was written?); ignored it";
        break;
      }
      fail(path, line, j.is_discarded() ? "not JSON" : "not a JSON object");
    }
    if (line == 1) {
      if (!j.contains("format") || j["format"] != kFormat)
        fail(path, line, std::string("not a session sidecar (no \"format\": \"") + kFormat + "\")");
      const int version = read<int>(j, "version", path, line);
      if (version != kSessionTimelineVersion)
        fail(path, line,
             "version " + std::to_string(version) + " (this program reads version " +
                 std::to_string(kSessionTimelineVersion) + ")");
      if (read<int>(j, "frame", path, line) != 0) fail(path, line, "the header is not at frame 0");
      t.start = parseStart(member(j, "start", path, line), path, line);
      const nlohmann::json& settings = member(j, "settings", path, line);
      if (!settings.is_object()) fail(path, line, "\"settings\" is not an object");
      for (const auto& [key, value] : fields())
        if (!settings.contains(key)) fail(path, line, "\"settings\" has no \"" + key + "\"");
      applyFields(settings, t.settings, {}, path, line);
      try {
        t.settings.validate();
      } catch (const core::InputError& e) {
        fail(path, line, e.what());
      }
      continue;
    }
    if (!j.contains("frame") || !j["frame"].is_number_integer() || j["frame"].get<long long>() < 0)
      fail(path, line, "no \"frame\" (a recorded frame index >= 0)");
    const long long frame = j["frame"].get<long long>();
    const int previous = lastFrame;
    if (frame < previous)
      fail(path, line,
           "frame " + std::to_string(frame) + " comes after frame " + std::to_string(previous) +
               " (lines must be in frame order)");
    if (frame > 100000000) fail(path, line, "frame " + std::to_string(frame) + " is too large");
    lastFrame = int(frame);
    if (j.contains("time_s")) {
      const auto& v = j["time_s"];
      if (j.size() != 2) fail(path, line, "a time line holds only \"frame\" and \"time_s\"");
      if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0)
        fail(path, line, "\"time_s\" is " + v.dump() + " (seconds >= 0)");
      if (!t.times.empty() && t.times.back().first == frame)
        fail(path, line, "a second time for frame " + std::to_string(frame));
      t.times.emplace_back(int(frame), v.get<double>());
      continue;
    }
    TimelineEntry e;
    e.frame = int(frame);
    e.line = line;
    e.settings = t.entries.empty() ? t.settings : t.entries.back().settings;
    if (j.contains("event")) {
      if (j.size() != 2) fail(path, line, "an event line holds only \"frame\" and \"event\"");
      const auto& v = j["event"];
      if (!v.is_string() || (v != "undo" && v != "redo"))
        fail(path, line, "\"event\" is " + v.dump() + " (undo or redo)");
      e.event = v.get<std::string>();
    } else {
      if (j.size() < 2) fail(path, line, "a change line changes nothing");
      applyFields(j, e.settings, {"frame"}, path, line);
      try {
        e.settings.validate();
      } catch (const core::InputError& x) {
        fail(path, line, x.what());
      }
    }
    t.entries.push_back(std::move(e));
  }
  if (line == 0) throw core::InputError(path.string() + ": empty (no header line)");
  return t;
}

void checkSessionStart(const SessionTimeline& t, const terrain::Terrain& planet,
                       const tracking::CameraCalibration& calib) {
  const SessionStart& s = t.start;
  const std::string where = t.path.string() + ":1: ";
  const int side = planet.grid().side();
  const std::uint32_t crc = io::heightsChecksum(planet.heights());
  if (side != s.gridSide || planet.chart().radius() != s.radius || crc != s.heightsCrc) {
    char ours[160];
    std::snprintf(ours, sizeof ours, "grid %d, radius %.17g m, heights CRC-32 %08x", side,
                  planet.chart().radius(), unsigned(crc));
    char theirs[160];
    std::snprintf(theirs, sizeof theirs, "grid %d, radius %.17g m, heights CRC-32 %08x", s.gridSide,
                  s.radius, unsigned(s.heightsCrc));
    throw core::InputError(
        where + "the recording starts from another planet (" + theirs +
        (s.planetFile.empty() ? ", the default planet of seed " + std::to_string(s.seed)
                              : ", " + s.planetFile) +
        ") than the one to replay onto (" + ours +
        "); give that planet with --planet, or --no-session to replay without the sidecar");
  }
  bool same =
      calib.imageSize == s.imageSize && int(calib.distortion.total()) == int(s.distortion.size());
  for (int i = 0; same && i < 9; ++i) same = calib.K(i / 3, i % 3) == s.K[i];
  for (int i = 0; same && i < int(s.distortion.size()); ++i)
    same = calib.distortion.at<double>(i) == s.distortion[i];
  if (!same)
    throw core::InputError(where + "the session was recorded with another calibration (" +
                           s.calibrationFile + ") than " + calib.source +
                           "; give that one with --calib, or --no-session");
}

TimelinePlayer::TimelinePlayer(const SessionTimeline& t, SessionControl& control)
    : t_(t), control_(control) {
  control_.apply(t.settings);
}

void TimelinePlayer::run(const TimelineEntry& e) {
  try {
    if (e.event == "undo")
      control_.undo();
    else if (e.event == "redo")
      control_.redo();
    else
      control_.apply(e.settings);
    ++applied_;
  } catch (const core::InputError& x) {
    warnings_.push_back(t_.path.string() + ":" + std::to_string(e.line) + ": " +
                        (e.event.empty() ? "change" : e.event) + " at frame " +
                        std::to_string(e.frame) + " refused (" + x.what() +
                        "): the replay differs from the session from there on");
  }
}

void TimelinePlayer::before(int frame) {
  while (next_ < t_.entries.size() && t_.entries[next_].frame <= frame) run(t_.entries[next_++]);
}

void TimelinePlayer::finish(int frames) {
  before(frames);
  if (next_ < t_.entries.size())
    warnings_.push_back(t_.path.string() + ":" + std::to_string(t_.entries[next_].line) +
                        ": changes at frame " + std::to_string(t_.entries[next_].frame) +
                        " and later were not applied: the video has only " +
                        std::to_string(frames) + " frames");
}

}  // namespace ps::replay
