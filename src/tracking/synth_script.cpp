// The synthetic scene's script: its JSON form (synth.hpp describes the schema), parsing with
// errors that name the field, and validation.
#include <cmath>
#include <fstream>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/synth.hpp"

namespace ps::tracking {

namespace {

double get(const nlohmann::json& j, const char* key, double fallback, const std::string& where) {
  if (!j.contains(key)) return fallback;
  if (!j[key].is_number()) throw core::InputError(where + "." + key + " is not a number");
  const double v = j[key].get<double>();
  if (!std::isfinite(v)) throw core::InputError(where + "." + key + " is not finite");
  return v;
}

// A layout given by file name (relative to `folder` unless absolute) or inline.
std::shared_ptr<const MarkerLayout> layoutOf(const nlohmann::json& j, const std::string& field,
                                             const std::filesystem::path& folder) {
  if (j.is_string()) {
    std::filesystem::path p = j.get<std::string>();
    if (p.is_relative() && !folder.empty()) p = folder / p;
    return std::make_shared<const MarkerLayout>(loadMarkerLayout(p));
  }
  if (j.is_object()) return std::make_shared<const MarkerLayout>(parseMarkerLayout(j, field));
  throw core::InputError(field + " is neither a layout file name nor a layout object");
}

// The keys' fields as the script names them ("group" "" : at the key's top level), in one list
// for reading and writing.
struct KeyField {
  const char* group;
  const char* name;
  double SynthKey::*member;
};
constexpr KeyField kKeyFields[] = {{"camera", "distance", &SynthKey::camDistance},
                                   {"camera", "elevation", &SynthKey::camElevationDeg},
                                   {"camera", "azimuth", &SynthKey::camAzimuthDeg},
                                   {"camera", "roll", &SynthKey::camRollDeg},
                                   {"camera", "pan", &SynthKey::camPanDeg},
                                   {"camera", "tilt", &SynthKey::camTiltDeg},
                                   {"tip", "lat", &SynthKey::tipLatDeg},
                                   {"tip", "lon", &SynthKey::tipLonDeg},
                                   {"tip", "height_mm", &SynthKey::tipHeightMm},
                                   {"tool", "tilt", &SynthKey::toolTiltDeg},
                                   {"tool", "turn", &SynthKey::toolTurnDeg},
                                   {"", "blur", &SynthKey::blur},
                                   {"", "noise", &SynthKey::noise},
                                   {"", "gain", &SynthKey::gain},
                                   {"", "occlusion", &SynthKey::occlusion},
                                   {"hand", "x", &SynthKey::handX},
                                   {"hand", "y", &SynthKey::handY},
                                   {"hand", "height", &SynthKey::handHeight},
                                   {"hand", "radius", &SynthKey::handRadius}};

}  // namespace

Eigen::Vector3d SynthScript::planetCentre() const {
  if (!board) return {0, 0, planetRadius};
  const Eigen::Vector3d c = *board->planetCentre;
  return {c.x(), c.y(), planetRadius};
}

CameraCalibration SynthScript::syntheticCamera(cv::Size size) {
  const double f = 0.9375 * size.width;
  auto c = CameraCalibration::pinhole(f, f, 0.5 * size.width - 0.5, 0.5 * size.height - 0.5, size);
  c.source = "synthetic camera";
  return c;
}

void SynthScript::validate() const {
  auto fail = [](const std::string& m) { throw core::InputError("synthetic scene: " + m); };
  if (size.width < 32 || size.height < 32 || size.width > 8192 || size.height > 8192)
    fail("size " + std::to_string(size.width) + "x" + std::to_string(size.height) +
         " is not in 32..8192");
  if (!(fps > 0 && fps <= 1000)) fail("fps " + std::to_string(fps) + " is not in (0, 1000]");
  familyInfo(family);
  if (!(planetMarkerSize > 0) || !(toolMarkerSize > 0) || !(planetRadius > 0))
    fail("marker sizes and the planet radius must be > 0");
  if (!board && !toolLayout && planetId == toolId) fail("planet and tool markers have the same id");
  if (board && !board->planetCentre) fail(board->source + ": a board needs planet_centre");
  if (board && !board->planar()) fail(board->source + ": a board's markers must lie in one plane");
  if (toolLayout && !toolLayout->tip) fail(toolLayout->source + ": a tool layout needs tip");
  // A layout's markers are of its own family, the single markers of `family`: ids clash within
  // one family only.
  const bool oneFamily =
      (board ? board->family : family) == (toolLayout ? toolLayout->family : family);
  const std::vector<int> toolIds = toolLayout ? toolLayout->ids() : std::vector<int>{toolId};
  for (int id : toolIds)
    if (oneFamily && (board ? board->find(id) != nullptr : id == planetId))
      fail("id " + std::to_string(id) + " is on both the planet's and the tool's markers");
  if (!tipOffset.allFinite() || tipOffset.norm() < 1e-3) fail("tool tip offset must be >= 1 mm");
  if (!(exposure >= 0 && exposure <= 1)) fail("exposure must be in [0, 1]");
  if (table != "wood" && table != "textured" && table != "plain")
    fail("table \"" + table + "\" is not wood, textured or plain");
  if (motionSamples < 1 || motionSamples > 32) fail("motion_samples must be in 1..32");
  if (keys.empty()) fail("no keys");
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const auto& k = keys[i];
    const std::string at =
        "key " + std::to_string(i) + " (frame " + std::to_string(int(k.frame)) + "): ";
    if (k.frame < 0 || k.frame != std::floor(k.frame))
      fail(at + "frame must be a whole number >= 0");
    if (i > 0 && !(k.frame > keys[i - 1].frame)) fail(at + "key frames must increase");
    if (!(k.camDistance > 0.05)) fail(at + "camera distance must be > 0.05 m");
    if (!(k.camElevationDeg > 0 && k.camElevationDeg < 90))
      fail(at + "camera elevation must be in (0, 90)");
    if (!(std::abs(k.camPanDeg) < 80 && std::abs(k.camTiltDeg) < 80))
      fail(at + "camera pan and tilt must be within +-80 degrees");
    if (!(k.tipLatDeg >= -90 && k.tipLatDeg <= 90)) fail(at + "tip latitude must be in [-90, 90]");
    if (!(k.toolTiltDeg >= -80 && k.toolTiltDeg <= 80)) fail(at + "tool tilt must be in [-80, 80]");
    if (!(k.blur >= 0 && k.blur < 20)) fail(at + "blur must be in [0, 20)");
    if (!(k.noise >= 0 && k.noise < 64)) fail(at + "noise must be in [0, 64)");
    if (!(k.gain > 0 && k.gain < 4)) fail(at + "gain must be in (0, 4)");
    if (!(k.occlusion >= 0 && k.occlusion <= 2)) fail(at + "occlusion must be in [0, 2]");
    if (!(k.handRadius >= 0 && k.handRadius <= 1)) fail(at + "hand radius must be in [0, 1] m");
    if (!(k.handHeight >= 0 && k.handHeight <= 1)) fail(at + "hand height must be in [0, 1] m");
  }
}

SynthScript parseSynthScript(const nlohmann::json& j, const std::string& source,
                             const std::filesystem::path& folder) {
  SynthScript s;
  try {
    if (!j.is_object()) throw core::InputError("not a JSON object");
    if (j.contains("size")) {
      const auto& z = j["size"];
      if (!z.is_array() || z.size() != 2 || !z[0].is_number_integer() || !z[1].is_number_integer())
        throw core::InputError("size must be [width, height]");
      s.size = {z[0].get<int>(), z[1].get<int>()};
    }
    s.camera = SynthScript::syntheticCamera(s.size);
    s.fps = get(j, "fps", s.fps, "");
    if (j.contains("seed")) s.seed = j["seed"].get<std::uint64_t>();
    if (j.contains("family")) s.family = j["family"].get<std::string>();
    if (j.contains("colour")) s.colour = j["colour"].get<bool>();
    if (j.contains("table")) s.table = j["table"].get<std::string>();
    if (j.contains("camera")) {
      const auto& c = j["camera"];
      s.camera = CameraCalibration::pinhole(get(c, "fx", s.camera.K(0, 0), "camera"),
                                            get(c, "fy", s.camera.K(1, 1), "camera"),
                                            get(c, "cx", s.camera.K(0, 2), "camera"),
                                            get(c, "cy", s.camera.K(1, 2), "camera"), s.size);
      s.camera.source = "synthetic camera";
      if (c.contains("distortion")) {
        // OpenCV's k1, k2, p1, p2, k3: the recording shows the lens a real webcam has.
        const auto& d = c["distortion"];
        if (!d.is_array() || d.size() != 5)
          throw core::InputError("camera.distortion must be [k1, k2, p1, p2, k3]");
        for (int i = 0; i < 5; ++i) {
          if (!d[std::size_t(i)].is_number())
            throw core::InputError("camera.distortion[" + std::to_string(i) + "] is not a number");
          s.camera.distortion.at<double>(0, i) = d[std::size_t(i)].get<double>();
        }
        s.camera.validate();
      }
    }
    if (j.contains("planet")) {
      const auto& p = j["planet"];
      s.planetId = int(get(p, "id", s.planetId, "planet"));
      s.planetMarkerSize = get(p, "size", s.planetMarkerSize, "planet");
      s.planetRadius = get(p, "radius", s.planetRadius, "planet");
    }
    if (j.contains("tool")) {
      const auto& t = j["tool"];
      s.toolId = int(get(t, "id", s.toolId, "tool"));
      s.toolMarkerSize = get(t, "size", s.toolMarkerSize, "tool");
      if (t.contains("tip")) {
        const auto& tip = t["tip"];
        if (!tip.is_array() || tip.size() != 3)
          throw core::InputError("tool.tip must be [x, y, z]");
        s.tipOffset = {tip[0].get<double>(), tip[1].get<double>(), tip[2].get<double>()};
      }
    }
    if (j.contains("board")) s.board = layoutOf(j["board"], "board", folder);
    if (j.contains("tool_layout")) {
      s.toolLayout = layoutOf(j["tool_layout"], "tool_layout", folder);
      if (s.toolLayout->tip) s.tipOffset = *s.toolLayout->tip;
    }
    s.exposure = get(j, "exposure", s.exposure, "");
    s.motionSamples = int(get(j, "motion_samples", s.motionSamples, ""));
    if (!j.contains("keys") || !j["keys"].is_array()) throw core::InputError("no keys array");
    SynthKey prev;
    for (std::size_t i = 0; i < j["keys"].size(); ++i) {
      const auto& k = j["keys"][i];
      const std::string at = "keys[" + std::to_string(i) + "]";
      SynthKey key = prev;
      if (!k.contains("frame")) throw core::InputError(at + " has no frame");
      key.frame = get(k, "frame", 0, at);
      for (const KeyField& field : kKeyFields) {
        const bool nested = field.group[0] != '\0';
        if (nested && !k.contains(field.group)) continue;
        key.*field.member = get(nested ? k[field.group] : k, field.name, key.*field.member,
                                nested ? at + "." + field.group : at);
      }
      s.keys.push_back(key);
      prev = key;
    }
    s.validate();
  } catch (const nlohmann::json::exception& e) {
    throw core::InputError(source + ": " + e.what());
  } catch (const core::InputError& e) {
    throw core::InputError(source + ": " + e.what());
  }
  return s;
}

SynthScript loadSynthScript(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw core::InputError(path.string() + ": cannot open the scene script");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {
    throw core::InputError(path.string() + ": " + e.what());
  }
  return parseSynthScript(j, path.string(), path.parent_path());
}

nlohmann::json toJson(const SynthScript& s) {
  nlohmann::json j = {
      {"size", {s.size.width, s.size.height}},
      {"fps", s.fps},
      {"seed", s.seed},
      {"family", s.family},
      {"colour", s.colour},
      {"camera",
       {{"fx", s.camera.K(0, 0)},
        {"fy", s.camera.K(1, 1)},
        {"cx", s.camera.K(0, 2)},
        {"cy", s.camera.K(1, 2)}}},
      {"planet", {{"id", s.planetId}, {"size", s.planetMarkerSize}, {"radius", s.planetRadius}}},
      {"tool",
       {{"id", s.toolId},
        {"size", s.toolMarkerSize},
        {"tip", {s.tipOffset.x(), s.tipOffset.y(), s.tipOffset.z()}}}},
      {"exposure", s.exposure},
      {"motion_samples", s.motionSamples}};
  if (s.table != "wood") j["table"] = s.table;
  if (cv::countNonZero(s.camera.distortion) > 0) {
    std::vector<double> d(5, 0.0);
    for (int i = 0; i < std::min(5, int(s.camera.distortion.total())); ++i)
      d[std::size_t(i)] = s.camera.distortion.at<double>(i);
    j["camera"]["distortion"] = d;
  }
  if (s.board) j["board"] = toJson(*s.board);
  if (s.toolLayout) j["tool_layout"] = toJson(*s.toolLayout);
  nlohmann::json keys = nlohmann::json::array();
  for (std::size_t i = 0; i < s.keys.size(); ++i) {
    const SynthKey& k = s.keys[i];
    nlohmann::json key = {{"frame", int(k.frame)}};
    // The hand only where one is (or was just before: its radius shrinking to 0 matters).
    const bool hand = k.handRadius > 0 || (i > 0 && s.keys[i - 1].handRadius > 0);
    for (const KeyField& field : kKeyFields) {
      if (std::string(field.group) == "hand" && !hand) continue;
      if (field.group[0] == '\0')
        key[field.name] = k.*field.member;
      else
        key[field.group][field.name] = k.*field.member;
    }
    keys.push_back(key);
  }
  j["keys"] = keys;
  return j;
}

}  // namespace ps::tracking
