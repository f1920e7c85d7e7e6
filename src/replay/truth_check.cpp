#include "replay/truth_check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <vector>

#include "core/input_error.hpp"

namespace ps::replay {

namespace {

using nlohmann::json;

// Each JSON line with a "frame" number, by frame; other lines (the truth's header) are skipped.
std::map<int, json> framesOf(std::istream& in, const std::string& name) {
  std::map<int, json> frames;
  std::string line;
  int lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    if (line.empty()) continue;
    json j = json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object())
      throw core::InputError(name + ":" + std::to_string(lineNo) + ": not a JSON object");
    if (!j.contains("frame")) continue;
    if (!j["frame"].is_number_integer())
      throw core::InputError(name + ":" + std::to_string(lineNo) + ": \"frame\" is not an integer");
    const int frame = j["frame"].get<int>();
    frames[frame] = std::move(j);
  }
  return frames;
}

// A 3-vector field, or nothing where it is absent, null or not three numbers.
std::optional<std::array<double, 3>> vec3(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key)) return std::nullopt;
  const json& v = j[key];
  if (!v.is_array() || v.size() != 3) return std::nullopt;
  std::array<double, 3> out{};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!v[i].is_number()) return std::nullopt;
    out[i] = v[i].get<double>();
  }
  return out;
}

double distanceMm(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return 1e3 * std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

json spread(std::vector<double> v) {
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) {
    return v[std::min(v.size() - 1, std::size_t(std::ceil(q * double(v.size())) - 1))];
  };
  const auto r3 = [](double x) { return std::round(x * 1e3) / 1e3; };
  return {
      {"median", r3(at(0.5))}, {"p95", r3(at(0.95))}, {"max", r3(v.back())}, {"frames", v.size()}};
}

bool flag(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_boolean() && j[key].get<bool>();
}

}  // namespace

std::filesystem::path truthPathFor(const std::filesystem::path& video) {
  std::filesystem::path p = video;
  p.replace_extension(".truth.jsonl");
  return p;
}

json TruthComparison::toJson() const {
  return {{"frames", frames},
          {"touching_frames", touching},
          {"sculpted_when_touching", sculptedWhenTouching},
          {"planet_in_view", planetVisible},
          {"pose_when_in_view", poseWhenVisible},
          {"tip_error_mm", tipErrorMm},
          {"planet_centre_error_mm", centreErrorMm}};
}

TruthComparison compareWithTruth(std::istream& truthIn, const std::string& truthName,
                                 std::istream& logIn, const std::string& logName) {
  const std::map<int, json> truth = framesOf(truthIn, truthName);
  const std::map<int, json> log = framesOf(logIn, logName);
  TruthComparison c;
  std::vector<double> tip, centre;
  for (const auto& [frame, t] : truth) {
    const auto it = log.find(frame);
    if (it == log.end()) continue;
    const json& l = it->second;
    ++c.frames;
    const json& tPlanet = t.contains("planet") ? t["planet"] : json();
    const json& lPlanet = l.contains("planet") ? l["planet"] : json();
    const bool pose = lPlanet.is_object() && lPlanet.value("state", "lost") != "lost";
    // A board is in view when one of its markers is at least half visible (the tracker can
    // read it); a single marker when all of it is.
    const bool inView =
        tPlanet.is_object() && tPlanet.contains("half_visible")
            ? tPlanet["half_visible"].is_number() && tPlanet["half_visible"].get<double>() >= 1
            : flag(tPlanet, "visible");
    c.planetVisible += inView;
    c.poseWhenVisible += inView && pose;
    if (flag(t, "touching")) {
      ++c.touching;
      c.sculptedWhenTouching += flag(l, "touching");
    }
    const auto tTip = vec3(t, "tip_planet"), lTip = vec3(l, "tip_planet_m");
    if (tTip && lTip && t.contains("tool") && flag(t["tool"], "visible"))
      tip.push_back(distanceMm(*tTip, *lTip));
    const auto tCentre = vec3(tPlanet, "centre_camera_m"),
               lCentre = vec3(lPlanet, "centre_camera_m");
    if (tCentre && lCentre && pose) centre.push_back(distanceMm(*tCentre, *lCentre));
  }
  c.tipErrorMm = spread(std::move(tip));
  c.centreErrorMm = spread(std::move(centre));
  return c;
}

}  // namespace ps::replay
