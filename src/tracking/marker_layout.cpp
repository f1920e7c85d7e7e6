#include "tracking/marker_layout.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"

namespace ps::tracking {

namespace {

// A corner set within this fraction of its edge of a perfect square is accepted: printed boards
// measured with a ruler are good to about 0.5 mm in 100 mm.
constexpr double kSquareTolerance = 0.005;

Eigen::Vector3d vec3(const nlohmann::json& j, double scale, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw core::InputError(where + " is not [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!j[std::size_t(i)].is_number()) throw core::InputError(where + " is not [x, y, z]");
    v[i] = j[std::size_t(i)].get<double>() * scale;
    if (!std::isfinite(v[i])) throw core::InputError(where + " is not finite");
  }
  return v;
}

void checkSquare(const LayoutMarker& m, const std::string& where) {
  const auto& c = m.corners;
  const double e = m.edge();
  if (!(e > 1e-4))
    throw core::InputError(where + ": edge " + core::exactNumber(e) + " m is not > 0.1 mm");
  for (int i = 0; i < 4; ++i) {
    const double ei = (c[std::size_t((i + 1) % 4)] - c[std::size_t(i)]).norm();
    if (std::abs(ei - e) > kSquareTolerance * e)
      throw core::InputError(where + ": not a square (edge " + std::to_string(i) + " is " +
                             core::exactNumber(ei) + " m, the mean edge " + core::exactNumber(e) +
                             " m)");
  }
  const double d0 = (c[2] - c[0]).norm(), d1 = (c[3] - c[1]).norm();
  if (std::abs(d0 - d1) > kSquareTolerance * e)
    throw core::InputError(where + ": not a square (diagonals " + core::exactNumber(d0) + " and " +
                           core::exactNumber(d1) + " m)");
  const Eigen::Vector3d n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
  const double off = std::abs(n.dot(c[3] - c[0]));
  if (off > kSquareTolerance * e)
    throw core::InputError(where + ": the four corners are not in one plane (the fourth is " +
                           core::exactNumber(off) + " m off the plane of the other three)");
}

}  // namespace

double LayoutMarker::edge() const {
  double sum = 0;
  for (int i = 0; i < 4; ++i)
    sum += (corners[std::size_t((i + 1) % 4)] - corners[std::size_t(i)]).norm();
  return sum / 4;
}

Pose LayoutMarker::inBody() const {
  const auto& c = corners;  // TL, TR, BR, BL
  const Eigen::Vector3d x = ((c[1] - c[0]) + (c[2] - c[3])).normalized();
  const Eigen::Vector3d yRough = ((c[0] - c[3]) + (c[1] - c[2])).normalized();
  const Eigen::Vector3d z = x.cross(yRough).normalized();
  Pose p;
  p.R.col(0) = x;
  p.R.col(1) = z.cross(x);
  p.R.col(2) = z;
  p.t = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  return p;
}

double MarkerLayout::stickBaseRadius() const {
  return stickRadius.value_or(kDefaultStickRadius);
}

double MarkerLayout::stickEndRadius() const {
  return stickTipRadius.value_or(stickBaseRadius());
}

const LayoutMarker* MarkerLayout::find(int id) const {
  for (const auto& m : markers)
    if (m.id == id) return &m;
  return nullptr;
}

std::vector<int> MarkerLayout::ids() const {
  std::vector<int> out;
  for (const auto& m : markers) out.push_back(m.id);
  return out;
}

bool MarkerLayout::planar() const {
  if (markers.empty()) return true;
  const Pose first = markers.front().inBody();
  const Eigen::Vector3d n = first.R.col(2);
  const double tolerance = kSquareTolerance * markers.front().edge();
  for (const auto& m : markers)
    for (const auto& c : m.corners)
      if (std::abs(n.dot(c - first.t)) > tolerance) return false;
  return true;
}

MarkerLayout MarkerLayout::singleMarker(int id, double size, const std::string& family) {
  MarkerLayout l;
  l.family = family;
  LayoutMarker m;
  m.id = id;
  m.corners = markerObjectPoints(size);
  l.markers.push_back(m);
  l.source = "single marker " + std::to_string(id);
  return l;
}

MarkerLayout parseMarkerLayout(const nlohmann::json& j, const std::string& source) {
  MarkerLayout l;
  l.source = source;
  auto fail = [&](const std::string& m) -> void { throw core::InputError(source + ": " + m); };
  if (!j.is_object()) fail("not a JSON object");
  if (!j.contains("family") || !j["family"].is_string()) fail("no \"family\" string");
  l.family = j["family"].get<std::string>();
  FamilyInfo family;
  try {
    family = familyInfo(l.family);
  } catch (const core::InputError& e) {
    fail(std::string("family: ") + e.what());
  }
  double scale = 1;
  if (j.contains("units")) {
    if (!j["units"].is_string()) fail("\"units\" is not a string");
    const auto u = j["units"].get<std::string>();
    if (u == "mm")
      scale = 1e-3;
    else if (u != "m")
      fail("units \"" + u + "\": expected \"m\" or \"mm\"");
  }
  if (!j.contains("markers") || !j["markers"].is_array() || j["markers"].empty())
    fail("no \"markers\" array with at least one marker");
  for (std::size_t i = 0; i < j["markers"].size(); ++i) {
    const auto& jm = j["markers"][i];
    std::string where = "markers[" + std::to_string(i) + "]";
    if (!jm.is_object()) fail(where + " is not an object");
    if (!jm.contains("id") || !jm["id"].is_number_integer()) fail(where + " has no integer \"id\"");
    LayoutMarker m;
    const auto id = jm["id"].get<long long>();
    where += " (id " + std::to_string(id) + ")";
    if (id < 0 || id >= family.markerCount)
      fail(where + ": id outside " + l.family + " (0.." + std::to_string(family.markerCount - 1) +
           ")");
    m.id = int(id);
    if (l.find(m.id)) fail(where + ": id " + std::to_string(m.id) + " appears twice");
    if (!jm.contains("corners") || !jm["corners"].is_array() || jm["corners"].size() != 4)
      fail(where + ": \"corners\" is not four [x, y, z] points (TL, TR, BR, BL)");
    try {
      for (std::size_t k = 0; k < 4; ++k)
        m.corners[k] = vec3(jm["corners"][k], scale, where + ".corners[" + std::to_string(k) + "]");
      checkSquare(m, where);
    } catch (const core::InputError& e) {
      fail(e.what());
    }
    l.markers.push_back(m);
  }
  try {
    if (j.contains("planet_centre"))
      l.planetCentre = vec3(j["planet_centre"], scale, "planet_centre");
    if (j.contains("tip")) l.tip = vec3(j["tip"], scale, "tip");
  } catch (const core::InputError& e) {
    fail(e.what());
  }
  auto radius = [&](const char* key) -> std::optional<double> {
    if (!j.contains(key)) return std::nullopt;
    const std::string name = std::string("\"") + key + "\"";
    if (!j[key].is_number()) fail(name + " is not a number");
    if (!l.tip) fail(name + " without a \"tip\" (a stick runs from the solid to the tip)");
    const double r = j[key].get<double>() * scale;
    if (!(r > 0) || !(r <= kMaxStickRadius))
      fail(name + " " + core::exactNumber(r) + " m is not in (0, " +
           core::exactNumber(kMaxStickRadius) + "] m");
    return r;
  };
  l.stickRadius = radius("stick_radius");
  l.stickTipRadius = radius("stick_tip_radius");
  return l;
}

MarkerLayout loadMarkerLayout(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw core::InputError(path.string() + ": cannot open the marker layout");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {
    throw core::InputError(path.string() + ": not JSON (" + e.what() + ")");
  }
  return parseMarkerLayout(j, path.string());
}

nlohmann::json toJson(const MarkerLayout& layout) {
  auto arr = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  nlohmann::json j;
  j["family"] = layout.family;
  j["units"] = "m";
  j["markers"] = nlohmann::json::array();
  for (const auto& m : layout.markers) {
    nlohmann::json c = nlohmann::json::array();
    for (const auto& p : m.corners) c.push_back(arr(p));
    j["markers"].push_back({{"id", m.id}, {"corners", c}});
  }
  if (layout.planetCentre) j["planet_centre"] = arr(*layout.planetCentre);
  if (layout.tip) j["tip"] = arr(*layout.tip);
  if (layout.stickRadius) j["stick_radius"] = *layout.stickRadius;
  if (layout.stickTipRadius) j["stick_tip_radius"] = *layout.stickTipRadius;
  return j;
}

MarkerLayout resizedLayout(const MarkerLayout& layout, const std::string& family,
                           double markerEdge) {
  if (layout.markers.empty()) throw core::InputError(layout.source + ": the layout has no markers");
  if (!(markerEdge >= 0) || !std::isfinite(markerEdge))
    throw core::InputError(layout.source + ": marker size " + std::to_string(markerEdge * 1e3) +
                           " mm is not > 0");
  double mean = 0;
  for (const auto& m : layout.markers) mean += m.edge();
  mean /= double(layout.markers.size());
  const double k = markerEdge > 0 ? markerEdge / mean : 1.0;
  MarkerLayout out = layout;
  if (!family.empty()) out.family = family;
  // A solid's faces hold their markers with the quiet zone (a cube of 40 mm tag36h11 markers is
  // 50 mm): in another family the faces move along their normals with the quiet zone's share
  // (the in-plane offsets and the markers scale by k), and the tip with them. A board scales.
  double faces = k;
  if (!layout.planar()) {
    const FamilyInfo from = familyInfo(layout.family), to = familyInfo(out.family);
    faces = k * (double(to.totalCells) / to.edgeCells) / (double(from.totalCells) / from.edgeCells);
  }
  for (auto& m : out.markers) {
    const Pose p = m.inBody();
    const Eigen::Vector3d n = p.R.col(2);
    const double d = p.t.dot(n);
    const Eigen::Vector3d centre = (p.t - d * n) * k + d * faces * n;
    for (auto& c : m.corners) c = centre + (c - p.t) * k;
  }
  if (out.planetCentre) *out.planetCentre *= k;
  if (out.tip) *out.tip *= faces;
  // Read back as a file would be: an id the family does not hold is named.
  MarkerLayout checked = parseMarkerLayout(toJson(out), layout.source);
  checked.source = layout.source;
  return checked;
}

std::string layoutFileText(const MarkerLayout& layout) {
  // Every field toJson writes (whatever a layout grows), numbers to the nanometre.
  nlohmann::json j = toJson(layout);
  std::function<void(nlohmann::json&)> round = [&](nlohmann::json& v) {
    if (v.is_number_float()) v = std::round(v.get<double>() * 1e9) / 1e9 + 0.0;  // no -0
    if (v.is_structured())
      for (auto& x : v) round(x);
  };
  round(j);
  std::string text = "{\n  \"family\": " + j["family"].dump() +
                     ",\n  \"units\": " + j["units"].dump() + ",\n  \"markers\": [\n";
  const auto& markers = j["markers"];
  for (std::size_t i = 0; i < markers.size(); ++i)
    text += "    " + markers[i].dump(-1, ' ', false) + (i + 1 < markers.size() ? ",\n" : "\n");
  text += "  ]";
  for (const auto& [key, value] : j.items())
    if (key != "family" && key != "units" && key != "markers")
      text += ",\n  " + nlohmann::json(key).dump() + ": " + value.dump();
  return text + "\n}\n";
}

std::filesystem::path defaultBoardPath(const std::filesystem::path& root) {
  return root / "markers" / "planet-board.json";
}
std::filesystem::path defaultToolLayoutPath(const std::filesystem::path& root) {
  return root / "markers" / "tool-cube.json";
}

}  // namespace ps::tracking
