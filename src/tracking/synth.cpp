#include "tracking/synth.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/render.hpp"

namespace ps::tracking {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kTableMetres = 1.2;
constexpr int kTablePixels = 1200;  // 1 mm per texel

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

Eigen::Vector3d unitDirection(double latDeg, double lonDeg) {
  const double la = latDeg * kDeg, lo = lonDeg * kDeg;
  return {std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la)};
}

// Any unit vector perpendicular to n.
Eigen::Vector3d perpendicular(const Eigen::Vector3d& n) {
  const Eigen::Vector3d a =
      std::abs(n.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  return n.cross(a).normalized();
}

// Component of v perpendicular to unit axis, normalised (fallback when v is along the axis).
Eigen::Vector3d orthogonalPart(const Eigen::Vector3d& v, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d w = v - v.dot(axis) * axis;
  return w.norm() > 1e-9 ? Eigen::Vector3d(w.normalized()) : perpendicular(axis);
}

cv::Matx33d toCv(const Eigen::Matrix3d& m) {
  cv::Matx33d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
  return r;
}

// Homography from the marker plane (z = 0, metres) to pixels.
cv::Matx33d planeHomography(const CameraCalibration& cam, const Pose& pose) {
  Eigen::Matrix3d M;
  M.col(0) = pose.R.col(0);
  M.col(1) = pose.R.col(1);
  M.col(2) = pose.t;
  return cam.K * toCv(M);
}

// The card texture (marker cells plus `margin` white cells) in cells -> marker plane metres.
cv::Matx33d cardToPlane(const FamilyInfo& info, int margin, double size) {
  const double c = size / info.edgeCells;
  const double mid = margin + info.edgeOffset + 0.5 * info.edgeCells;
  return {c, 0, -mid * c, 0, -c, mid * c, 0, 0, 1};
}

cv::Mat makeCard(const std::string& family, int id, int margin) {
  cv::Mat card;
  cv::copyMakeBorder(markerCells(family, id), card, margin, margin, margin, margin,
                     cv::BORDER_CONSTANT, cv::Scalar(255));
  // Paper is not perfectly white, ink not perfectly black.
  card.convertTo(card, CV_8U, (235.0 - 25.0) / 255.0, 25.0);
  return card;
}

cv::Mat makeTable(std::uint64_t seed) {
  cv::RNG rng(seed * 2654435761ULL + 17);
  // Smooth shading (fine texture would make the lossless video large for nothing).
  cv::Mat coarse(8, 8, CV_32F), a;
  rng.fill(coarse, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::resize(coarse, a, {kTablePixels, kTablePixels}, 0, 0, cv::INTER_CUBIC);
  // Two-level shading: flat areas compress to almost nothing in FFV1, the soft edges between
  // them are still texture for the detectors to ignore.
  cv::Mat shade;
  cv::threshold(a, shade, 0.5, 1.0, cv::THRESH_BINARY);
  cv::GaussianBlur(shade, shade, cv::Size(0, 0), 3.0);
  shade = 0.7 + 0.2 * shade;
  std::vector<cv::Mat> ch = {shade * 70.0, shade * 115.0, shade * 160.0};  // B, G, R: wood
  cv::Mat table;
  cv::merge(ch, table);
  table.convertTo(table, CV_8UC3);
  // Clutter: paper scraps, dark objects and pen strokes (no valid markers).
  for (int i = 0; i < 30; ++i) {
    const cv::Point2f c(float(rng.uniform(0.0, double(kTablePixels))),
                        float(rng.uniform(0.0, double(kTablePixels))));
    const cv::Size2f s(float(rng.uniform(20.0, 90.0)), float(rng.uniform(20.0, 90.0)));
    const cv::RotatedRect r(c, s, float(rng.uniform(0.0, 180.0)));
    cv::Point2f p[4];
    r.points(p);
    std::vector<cv::Point> poly(p, p + 4);
    const int v = rng.uniform(0, 2) ? rng.uniform(10, 60) : rng.uniform(180, 250);
    cv::fillConvexPoly(table, poly, cv::Scalar(v, v, v), cv::LINE_AA);
  }
  for (int i = 0; i < 12; ++i) {
    const cv::Point p0(rng.uniform(0, kTablePixels), rng.uniform(0, kTablePixels));
    const cv::Point p1 = p0 + cv::Point(rng.uniform(-200, 200), rng.uniform(-200, 200));
    cv::line(table, p0, p1, cv::Scalar(rng.uniform(0, 80), rng.uniform(0, 80), rng.uniform(0, 80)),
             rng.uniform(2, 6), cv::LINE_AA);
  }
  return table;
}

double get(const nlohmann::json& j, const char* key, double fallback, const std::string& where) {
  if (!j.contains(key)) return fallback;
  if (!j[key].is_number()) throw core::InputError(where + "." + key + " is not a number");
  const double v = j[key].get<double>();
  if (!std::isfinite(v)) throw core::InputError(where + "." + key + " is not finite");
  return v;
}

}  // namespace

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
  if (planetId == toolId) fail("planet and tool markers have the same id");
  if (!tipOffset.allFinite() || tipOffset.norm() < 1e-3) fail("tool tip offset must be >= 1 mm");
  if (!(exposure >= 0 && exposure <= 1)) fail("exposure must be in [0, 1]");
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
    if (!(k.tipLatDeg >= -90 && k.tipLatDeg <= 90)) fail(at + "tip latitude must be in [-90, 90]");
    if (!(k.toolTiltDeg >= -80 && k.toolTiltDeg <= 80)) fail(at + "tool tilt must be in [-80, 80]");
    if (!(k.blur >= 0 && k.blur < 20)) fail(at + "blur must be in [0, 20)");
    if (!(k.noise >= 0 && k.noise < 64)) fail(at + "noise must be in [0, 64)");
    if (!(k.gain > 0 && k.gain < 4)) fail(at + "gain must be in (0, 4)");
    if (!(k.occlusion >= 0 && k.occlusion <= 2)) fail(at + "occlusion must be in [0, 2]");
  }
}

SynthScript parseSynthScript(const nlohmann::json& j, const std::string& source) {
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
    if (j.contains("camera")) {
      const auto& c = j["camera"];
      s.camera = CameraCalibration::pinhole(get(c, "fx", s.camera.K(0, 0), "camera"),
                                            get(c, "fy", s.camera.K(1, 1), "camera"),
                                            get(c, "cx", s.camera.K(0, 2), "camera"),
                                            get(c, "cy", s.camera.K(1, 2), "camera"), s.size);
      s.camera.source = "synthetic camera";
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
      if (k.contains("camera")) {
        const auto& c = k["camera"];
        key.camDistance = get(c, "distance", key.camDistance, at + ".camera");
        key.camElevationDeg = get(c, "elevation", key.camElevationDeg, at + ".camera");
        key.camAzimuthDeg = get(c, "azimuth", key.camAzimuthDeg, at + ".camera");
        key.camRollDeg = get(c, "roll", key.camRollDeg, at + ".camera");
      }
      if (k.contains("tip")) {
        const auto& t = k["tip"];
        key.tipLatDeg = get(t, "lat", key.tipLatDeg, at + ".tip");
        key.tipLonDeg = get(t, "lon", key.tipLonDeg, at + ".tip");
        key.tipHeightMm = get(t, "height_mm", key.tipHeightMm, at + ".tip");
      }
      if (k.contains("tool")) {
        const auto& t = k["tool"];
        key.toolTiltDeg = get(t, "tilt", key.toolTiltDeg, at + ".tool");
        key.toolTurnDeg = get(t, "turn", key.toolTurnDeg, at + ".tool");
      }
      key.blur = get(k, "blur", key.blur, at);
      key.noise = get(k, "noise", key.noise, at);
      key.gain = get(k, "gain", key.gain, at);
      key.occlusion = get(k, "occlusion", key.occlusion, at);
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
  return parseSynthScript(j, path.string());
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
  nlohmann::json keys = nlohmann::json::array();
  for (const auto& k : s.keys)
    keys.push_back(
        {{"frame", int(k.frame)},
         {"camera",
          {{"distance", k.camDistance},
           {"elevation", k.camElevationDeg},
           {"azimuth", k.camAzimuthDeg},
           {"roll", k.camRollDeg}}},
         {"tip", {{"lat", k.tipLatDeg}, {"lon", k.tipLonDeg}, {"height_mm", k.tipHeightMm}}},
         {"tool", {{"tilt", k.toolTiltDeg}, {"turn", k.toolTurnDeg}}},
         {"blur", k.blur},
         {"noise", k.noise},
         {"gain", k.gain},
         {"occlusion", k.occlusion}});
  j["keys"] = keys;
  return j;
}

nlohmann::json FrameTruth::toJson() const {
  auto v3 = [](const Eigen::Vector3d& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  auto pose = [&](const Pose& p) {
    return nlohmann::json{{"rvec", v3(p.rvec())}, {"tvec", v3(p.t)}};
  };
  nlohmann::json pl = pose(planet), to = pose(tool);
  pl["visible"] = planetVisible;
  pl["occluded"] = planetOccluded;
  pl["tilt_deg"] = planetTiltDeg;
  to["visible"] = toolVisible;
  to["occluded"] = toolOccluded;
  to["tilt_deg"] = toolTiltDeg;
  return {{"frame", frame},
          {"time", time},
          {"camera", pose(camera)},
          {"planet", pl},
          {"tool", to},
          {"tip_camera", v3(tipCamera)},
          {"tip_planet", v3(tipPlanet)},
          {"tip_height_m", tipHeight}};
}

SynthRenderer::SynthRenderer(SynthScript script) : script_(std::move(script)) {
  script_.validate();
  table_ = makeTable(script_.seed);
  planetCard_ = makeCard(script_.family, script_.planetId, planetMargin_);
  toolCard_ = makeCard(script_.family, script_.toolId, toolMargin_);
}

SynthKey SynthRenderer::keyAt(double f) const {
  const auto& keys = script_.keys;
  if (f <= keys.front().frame) return keys.front();
  if (f >= keys.back().frame) return keys.back();
  std::size_t i = 0;
  while (i + 1 < keys.size() && keys[i + 1].frame < f) ++i;
  const SynthKey &a = keys[i], &b = keys[i + 1];
  const double s = smoothstep((f - a.frame) / (b.frame - a.frame));
  auto mix = [s](double x, double y) { return x + s * (y - x); };
  SynthKey k;
  k.frame = f;
  k.camDistance = mix(a.camDistance, b.camDistance);
  k.camElevationDeg = mix(a.camElevationDeg, b.camElevationDeg);
  k.camAzimuthDeg = mix(a.camAzimuthDeg, b.camAzimuthDeg);
  k.camRollDeg = mix(a.camRollDeg, b.camRollDeg);
  k.tipLatDeg = mix(a.tipLatDeg, b.tipLatDeg);
  k.tipLonDeg = mix(a.tipLonDeg, b.tipLonDeg);
  k.tipHeightMm = mix(a.tipHeightMm, b.tipHeightMm);
  k.toolTiltDeg = mix(a.toolTiltDeg, b.toolTiltDeg);
  k.toolTurnDeg = mix(a.toolTurnDeg, b.toolTurnDeg);
  k.blur = mix(a.blur, b.blur);
  k.noise = mix(a.noise, b.noise);
  k.gain = mix(a.gain, b.gain);
  k.occlusion = mix(a.occlusion, b.occlusion);
  return k;
}

void SynthRenderer::poses(const SynthKey& k, Pose& camera, Pose& tool) const {
  const double r = script_.planetRadius;
  const Eigen::Vector3d centre(0, 0, r);
  const Eigen::Vector3d C =
      centre + k.camDistance * unitDirection(k.camElevationDeg, k.camAzimuthDeg);
  const Eigen::Vector3d z = (centre - C).normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Vector3d y = z.cross(x);
  const double roll = k.camRollDeg * kDeg;
  const Eigen::Vector3d xr = std::cos(roll) * x + std::sin(roll) * y;
  y = z.cross(xr);
  x = xr;
  camera.R.row(0) = x.transpose();
  camera.R.row(1) = y.transpose();
  camera.R.row(2) = z.transpose();
  camera.t = -(camera.R * C);

  // Tool: the tip on its spot; the stick (tip -> marker) across the line of sight, pointing
  // away from the planet as seen from the camera, then leaned toward the camera by `tilt`; the
  // marker's face turned away from the camera about the stick by `turn`.
  const Eigen::Vector3d n = unitDirection(k.tipLatDeg, k.tipLonDeg);
  const Eigen::Vector3d tip = centre + (r + 1e-3 * k.tipHeightMm) * n;
  const Eigen::Vector3d toCam = (C - tip).normalized();
  const Eigen::Vector3d across = orthogonalPart(n, toCam);
  const double tilt = k.toolTiltDeg * kDeg;
  const Eigen::Vector3d a = std::cos(tilt) * across + std::sin(tilt) * toCam;
  Eigen::Vector3d face = orthogonalPart(toCam, a);
  const double turn = k.toolTurnDeg * kDeg;
  face = std::cos(turn) * face + std::sin(turn) * a.cross(face);
  // Marker-frame basis: e1 = -tipOffset direction, e2 = the normal's part orthogonal to e1.
  const Eigen::Vector3d e1 = (-script_.tipOffset).normalized();
  const Eigen::Vector3d e2 = orthogonalPart(Eigen::Vector3d::UnitZ(), e1);
  Eigen::Matrix3d E, F;
  E << e1, e2, e1.cross(e2);
  F << a, face, a.cross(face);
  const Eigen::Matrix3d Rw = F * E.transpose();  // tool marker -> world
  const Eigen::Vector3d mc = tip - Rw * script_.tipOffset;
  tool.R = camera.R * Rw;
  tool.t = camera.R * mc + camera.t;
}

FrameTruth SynthRenderer::truth(double frame) const {
  const SynthKey k = keyAt(frame);
  FrameTruth t;
  t.frame = int(frame);
  t.time = frame / script_.fps;
  poses(k, t.camera, t.tool);
  t.planet = t.camera;  // the planet marker's frame is the world
  t.tipCamera = t.tool.apply(script_.tipOffset);
  const Pose planetFrame =
      t.planet * Pose{Eigen::Matrix3d::Identity(), {0, 0, script_.planetRadius}};
  t.tipPlanet = planetFrame.inverse().apply(t.tipCamera);
  t.tipHeight = t.tipPlanet.norm() - script_.planetRadius;
  auto visible = [&](const Pose& p, double size, double& tiltDeg) {
    const Eigen::Vector3d normal = p.R.col(2);
    const Eigen::Vector3d toCam = -p.t.normalized();
    tiltDeg = std::acos(std::clamp(normal.dot(toCam), -1.0, 1.0)) / kDeg;
    if (normal.dot(toCam) <= 0) return false;
    for (const auto& c : markerObjectPoints(size)) {
      const Eigen::Vector3d x = p.apply(c);
      if (x.z() <= 0) return false;
      const double u = script_.camera.K(0, 0) * x.x() / x.z() + script_.camera.K(0, 2);
      const double v = script_.camera.K(1, 1) * x.y() / x.z() + script_.camera.K(1, 2);
      if (u < 2 || v < 2 || u > script_.size.width - 3 || v > script_.size.height - 3) return false;
    }
    return true;
  };
  t.planetVisible = visible(t.planet, script_.planetMarkerSize, t.planetTiltDeg);
  t.toolVisible = visible(t.tool, script_.toolMarkerSize, t.toolTiltDeg);
  const Overlays o = overlays(k, t.camera, t.tool);
  // The marker with its quiet zone (one cell of white around the black border): covering the
  // quiet zone is enough to spoil a detection.
  const FamilyInfo info = familyInfo(script_.family);
  const auto pq = projectMarker(
      t.planet, script_.planetMarkerSize * (info.edgeCells + 2.0) / info.edgeCells, script_.camera);
  const auto tq = projectMarker(
      t.tool, script_.toolMarkerSize * (info.edgeCells + 2.0) / info.edgeCells, script_.camera);
  const std::vector<cv::Point2f> planetQuad(pq.begin(), pq.end()), toolQuad(tq.begin(), tq.end());
  auto overlaps = [](const std::vector<cv::Point2f>& a, const std::vector<cv::Point2d>& b) {
    if (b.size() < 3) return false;
    std::vector<cv::Point2f> bf(b.begin(), b.end()), inter;
    return cv::intersectConvexConvex(a, bf, inter) > 0.01;
  };
  auto discOver = [&](const std::vector<cv::Point2f>& q) {
    if (o.discRadius <= 0) return false;
    if (cv::pointPolygonTest(q, cv::Point2f(o.disc), true) > -o.discRadius) return true;
    return false;
  };
  t.planetOccluded = overlaps(planetQuad, o.toolCard) ||
                     (o.stickOk && overlaps(planetQuad, o.stick)) || discOver(planetQuad);
  t.toolOccluded = discOver(toolQuad);
  t.planetVisible = t.planetVisible && !t.planetOccluded;
  t.toolVisible = t.toolVisible && !t.toolOccluded;
  return t;
}

cv::Mat SynthRenderer::background(const Pose& camera) const {
  const cv::Size size = script_.size;
  // Table texel index (i, j) -> table plane metres -> pixels.
  const double s = kTableMetres / kTablePixels;
  const cv::Matx33d texToPlane(s, 0, -0.5 * kTableMetres + 0.5 * s, 0, -s,
                               0.5 * kTableMetres - 0.5 * s, 0, 0, 1);
  const cv::Matx33d H = planeHomography(script_.camera, camera) * texToPlane;
  cv::Mat out;
  cv::warpPerspective(table_, out, H, size, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                      cv::Scalar(150, 150, 145));
  // Pixels whose ray does not reach the table in front of the camera see the wall.
  const cv::Matx33d Kinv = script_.camera.K.inv();
  const Eigen::Vector3d rowz = camera.R.transpose().row(2);  // world z of a camera-frame vector
  const cv::Vec3d l = Kinv.t() * cv::Vec3d(rowz.x(), rowz.y(), rowz.z());
  for (int yy = 0; yy < size.height; ++yy) {
    auto* p = out.ptr<cv::Vec3b>(yy);
    for (int xx = 0; xx < size.width; ++xx)
      if (l[0] * xx + l[1] * yy + l[2] >= 0) {
        const uchar g = uchar(120 + 60 * yy / size.height);
        p[xx] = {g, g, uchar(g - 5)};
      }
  }
  return out;
}

SynthRenderer::Overlays SynthRenderer::overlays(const SynthKey& k, const Pose& camera,
                                                const Pose& tool) const {
  Overlays o;
  const FamilyInfo info = familyInfo(script_.family);
  const auto& K = script_.camera.K;
  auto project = [&](const Pose& pose, const Eigen::Vector3d& p, cv::Point2d& px) {
    const Eigen::Vector3d x = pose.apply(p);
    if (x.z() <= 1e-3) return false;
    px = {K(0, 0) * x.x() / x.z() + K(0, 2), K(1, 1) * x.y() / x.z() + K(1, 2)};
    return std::abs(px.x) < 1e5 && std::abs(px.y) < 1e5;
  };
  // The tool's card.
  const double cell = script_.toolMarkerSize / info.edgeCells;
  const double half = 0.5 * script_.toolMarkerSize + (info.edgeOffset + toolMargin_) * cell;
  bool ok = true;
  for (const auto& c : {Eigen::Vector3d(-half, half, 0), Eigen::Vector3d(half, half, 0),
                        Eigen::Vector3d(half, -half, 0), Eigen::Vector3d(-half, -half, 0)}) {
    cv::Point2d px;
    ok = project(tool, c, px) && ok;
    o.toolCard.push_back(px);
  }
  if (!ok) o.toolCard.clear();
  // The stick, from the card's edge to the tip.
  const Eigen::Vector3d d = script_.tipOffset.normalized();
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(d).normalized();
  const double w0 = 0.005, w1 = 0.002;
  o.stickOk = true;
  for (const auto& p :
       {Eigen::Vector3d(d * half + side * w0), Eigen::Vector3d(d * half - side * w0),
        Eigen::Vector3d(script_.tipOffset - side * w1),
        Eigen::Vector3d(script_.tipOffset + side * w1)}) {
    cv::Point2d px;
    o.stickOk = project(tool, p, px) && o.stickOk;
    o.stick.push_back(px);
  }
  // The hand.
  if (k.occlusion > 0) {
    const auto c = projectMarker(camera, script_.planetMarkerSize, script_.camera);
    if (std::abs(c[1].x) < 1e5 && std::abs(c[1].y) < 1e5) {
      o.disc = c[1];
      o.discRadius = k.occlusion * cv::norm(c[0] - c[2]);
    }
  }
  return o;
}

cv::Mat SynthRenderer::render(int frame) const {
  const SynthKey k = keyAt(frame);
  Pose camera, tool;
  poses(k, camera, tool);
  cv::Mat img = background(camera);

  // Sub-frame poses for motion blur.
  std::vector<Pose> cams, tools;
  const int n = script_.exposure > 0 ? script_.motionSamples : 1;
  for (int i = 0; i < n; ++i) {
    const double f = n == 1 ? frame : frame + script_.exposure * (double(i) / (n - 1) - 0.5);
    Pose c, t;
    poses(keyAt(f), c, t);
    cams.push_back(c);
    tools.push_back(t);
  }
  const FamilyInfo info = familyInfo(script_.family);
  std::vector<cv::Matx33d> hp, ht;
  for (int i = 0; i < n; ++i) {
    hp.push_back(planeHomography(script_.camera, cams[std::size_t(i)]) *
                 cardToPlane(info, planetMargin_, script_.planetMarkerSize));
    ht.push_back(planeHomography(script_.camera, tools[std::size_t(i)]) *
                 cardToPlane(info, toolMargin_, script_.toolMarkerSize));
  }
  drawTexturedQuadBlurred(img, planetCard_, hp, 8);

  const Overlays o = overlays(k, camera, tool);
  if (o.stickOk) {
    std::vector<cv::Point> poly;
    for (const auto& q : o.stick)
      poly.emplace_back(int(std::lround(q.x * 16)), int(std::lround(q.y * 16)));
    cv::fillConvexPoly(img, poly, cv::Scalar(40, 60, 90), cv::LINE_AA, 4);
  }
  drawTexturedQuadBlurred(img, toolCard_, ht, 8);

  if (o.discRadius > 0.5)  // a hand over the planet marker's top-right corner
    cv::circle(img, cv::Point(int(std::lround(o.disc.x * 16)), int(std::lround(o.disc.y * 16))),
               int(std::lround(o.discRadius * 16)), cv::Scalar(110, 140, 190), cv::FILLED,
               cv::LINE_AA, 4);

  cv::Mat f;
  img.convertTo(f, CV_32F, k.gain);
  if (k.blur > 0.05) cv::GaussianBlur(f, f, cv::Size(0, 0), k.blur);
  if (k.noise > 0) {
    cv::RNG rng(script_.seed * 0x9E3779B97F4A7C15ULL + std::uint64_t(frame) * 7919ULL + 1);
    cv::Mat noise(f.size(), f.type());
    rng.fill(noise, cv::RNG::NORMAL, 0.0, k.noise);
    f += noise;
  }
  cv::Mat out;
  f.convertTo(out, CV_8U);
  if (!script_.colour) cv::cvtColor(out, out, cv::COLOR_BGR2GRAY);
  return out;
}

}  // namespace ps::tracking
