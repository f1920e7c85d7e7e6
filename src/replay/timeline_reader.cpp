#include "replay/session_timeline.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <type_traits>
#include <utility>

#include "core/chart_factory.hpp"
#include "core/grid.hpp"
#include "core/input_error.hpp"
#include "io/stroke_journal.hpp"
#include "sand/material.hpp"
#include "tracking/marker_layout.hpp"

namespace ps::replay {

namespace {

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
      {"material", [](auto& s, auto& v) { s.displace.material = sand::Material::preset(text(v)); }},
      {"planet_radius_m", [](auto& s, auto& v) { s.planetRadius = number(v); }},
      {"spin_deg", [](auto& s, auto& v) { s.spinDeg = number(v); }},
      {"tilt_deg", [](auto& s, auto& v) { s.tiltDeg = number(v); }},
  };
  return f;
}

// Sidecars before 2026-12-07 name no material: theirs was sand, the settings' default.
constexpr const char* kMaterialKey = "material";

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
  if (planet.contains("chart")) {
    s.chart = read<std::string>(planet, "chart", path, line);
    s.chartNamed = true;
    try {
      core::chartShapeFromString(s.chart);
    } catch (const core::InputError& e) {
      fail(path, line, std::string("\"chart\": ") + e.what());
    }
  }
  s.radius = read<double>(planet, "radius_m", path, line);
  // A torus's and a cylinder's other dimension (sidecars of spheres have neither).
  if (planet.contains("minor_radius_m"))
    s.minorRadius = read<double>(planet, "minor_radius_m", path, line);
  if (planet.contains("length_m")) s.length = read<double>(planet, "length_m", path, line);
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

}  // namespace

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
      if (!j.contains("format") || j["format"] != kSessionFormat)
        fail(path, line,
             std::string("not a session sidecar (no \"format\": \"") + kSessionFormat + "\")");
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
        if (!settings.contains(key) && key != kMaterialKey)
          fail(path, line, "\"settings\" has no \"" + key + "\"");
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
  // A sphere's radius is its chart's radius(); a torus's and a cylinder's, their dimensions.
  const core::ChartDims dims = core::dimsOf(planet.chart());
  if (side != s.gridSide || planet.chart().name() != s.chart || dims.radius != s.radius ||
      dims.minorRadius != s.minorRadius || dims.length != s.length || crc != s.heightsCrc) {
    char ours[200];
    std::snprintf(ours, sizeof ours, "%s grid %d, radius %.17g m, heights CRC-32 %08x",
                  planet.chart().name().c_str(), side, dims.radius, unsigned(crc));
    char theirs[200];
    std::snprintf(theirs, sizeof theirs, "%s grid %d, radius %.17g m, heights CRC-32 %08x",
                  s.chart.c_str(), s.gridSide, s.radius, unsigned(s.heightsCrc));
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

}  // namespace ps::replay
