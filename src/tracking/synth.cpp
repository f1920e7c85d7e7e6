#include "tracking/synth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/synth_internal.hpp"
#include "tracking/textured_quad.hpp"

namespace ps::tracking {

using namespace synth_detail;

namespace {

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

// Over the wood, a fine pattern the size of a few pixels at arm's length: dark and light specks,
// chips and short grain strokes (a worn, speckled table top), seeded, so that every patch of the
// table has corners to follow.
void addFineTexture(cv::Mat& table, std::uint64_t seed) {
  cv::RNG rng(seed * 0x9E3779B97F4A7C15ULL + 101);
  for (int i = 0; i < 9000; ++i) {
    const cv::Point2f c(float(rng.uniform(0.0, double(kTablePixels))),
                        float(rng.uniform(0.0, double(kTablePixels))));
    const int v = rng.uniform(0, 2) ? rng.uniform(20, 90) : rng.uniform(170, 240);
    const cv::Scalar colour(v * 0.8, v * 0.95, v);
    if (i % 3 == 0) {
      cv::circle(table, c, rng.uniform(1, 5), colour, cv::FILLED, cv::LINE_AA);
    } else {
      const cv::RotatedRect r(
          c, cv::Size2f(float(rng.uniform(3.0, 14.0)), float(rng.uniform(2.0, 9.0))),
          float(rng.uniform(0.0, 180.0)));
      cv::Point2f p[4];
      r.points(p);
      std::vector<cv::Point> poly(p, p + 4);
      cv::fillConvexPoly(table, poly, colour, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(table, table, cv::Size(0, 0), 0.6);
}

cv::Mat makeTable(std::uint64_t seed, const std::string& kind) {
  if (kind == "plain")
    return cv::Mat(kTablePixels, kTablePixels, CV_8UC3, cv::Scalar(80, 120, 150));
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
  if (kind == "textured") addFineTexture(table, seed);
  return table;
}

}  // namespace

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
  if (!boardVisible.empty()) {
    // Scenes with rigid marker sets: what each marker shows, for the tracking benchmarks.
    nlohmann::json markers = nlohmann::json::array();
    for (const auto& [id, seen] : boardVisible) markers.push_back({{"id", id}, {"visible", seen}});
    pl["markers"] = markers;
    pl["half_visible"] = boardHalfVisible;
    pl["centre_camera_m"] = v3(planetCentreCamera);
  }
  nlohmann::json j = {{"frame", frame},
                      {"time", time},
                      {"camera", pose(camera)},
                      {"planet", pl},
                      {"tool", to},
                      {"tip_camera", v3(tipCamera)},
                      {"tip_planet", v3(tipPlanet)},
                      {"tip_height_m", tipHeight}};
  if (!boardVisible.empty()) j["camera_still"] = cameraStill;
  return j;
}

SynthRenderer::SynthRenderer(SynthScript script) : script_(std::move(script)) {
  script_.validate();
  table_ = makeTable(script_.seed, script_.table);
  planetCard_ = makeCard(script_.family, script_.planetId, planetMargin_);
  toolCard_ = makeCard(script_.family, script_.toolId, toolMargin_);
  if (script_.board)
    for (const auto& m : script_.board->markers)
      boardCards_.push_back(makeCard(script_.board->family, m.id, 0));
  if (script_.toolLayout)
    for (const auto& m : script_.toolLayout->markers)
      toolFaceCards_.push_back(makeCard(script_.toolLayout->family, m.id, 0));
  if (cv::countNonZero(script_.camera.distortion) > 0) {
    // Each frame pixel's ray, undistorted: the scene is drawn through a pinhole and then
    // resampled there, so the frame shows what the lens shows.
    const cv::Size size = script_.size;
    std::vector<cv::Point2f> pixels;
    pixels.reserve(std::size_t(size.area()));
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x) pixels.emplace_back(float(x), float(y));
    std::vector<cv::Point2f> pinhole;
    cv::undistortPoints(
        pixels, pinhole, cv::Mat(script_.camera.K), script_.camera.distortion, cv::noArray(),
        cv::Mat(script_.camera.K),
        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 40, 1e-6));
    distortMapX_.create(size, CV_32F);
    distortMapY_.create(size, CV_32F);
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x) {
        const cv::Point2f& p = pinhole[std::size_t(y) * std::size_t(size.width) + std::size_t(x)];
        distortMapX_.at<float>(y, x) = p.x;
        distortMapY_.at<float>(y, x) = p.y;
      }
  }
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
  k.camPanDeg = mix(a.camPanDeg, b.camPanDeg);
  k.camTiltDeg = mix(a.camTiltDeg, b.camTiltDeg);
  k.tipLatDeg = mix(a.tipLatDeg, b.tipLatDeg);
  k.tipLonDeg = mix(a.tipLonDeg, b.tipLonDeg);
  k.tipHeightMm = mix(a.tipHeightMm, b.tipHeightMm);
  k.toolTiltDeg = mix(a.toolTiltDeg, b.toolTiltDeg);
  k.toolTurnDeg = mix(a.toolTurnDeg, b.toolTurnDeg);
  k.blur = mix(a.blur, b.blur);
  k.noise = mix(a.noise, b.noise);
  k.gain = mix(a.gain, b.gain);
  k.occlusion = mix(a.occlusion, b.occlusion);
  k.handX = mix(a.handX, b.handX);
  k.handY = mix(a.handY, b.handY);
  k.handHeight = mix(a.handHeight, b.handHeight);
  k.handRadius = mix(a.handRadius, b.handRadius);
  return k;
}

void SynthRenderer::poses(const SynthKey& k, Pose& camera, Pose& tool) const {
  const double r = script_.planetRadius;
  const Eigen::Vector3d centre = script_.planetCentre();
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
  const Eigen::Matrix3d aim = (Eigen::AngleAxisd(-k.camTiltDeg * kDeg, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(k.camPanDeg * kDeg, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
  camera.R = aim * camera.R;
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

bool SynthRenderer::markerInView(const Pose& p, double size, double& tiltDeg) const {
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
}

FrameTruth SynthRenderer::truth(double frame) const {
  const SynthKey k = keyAt(frame);
  FrameTruth t;
  t.frame = int(frame);
  t.time = frame / script_.fps;
  poses(k, t.camera, t.tool);
  t.planet = t.camera;  // the planet marker's frame is the world
  t.tipCamera = t.tool.apply(script_.tipOffset);
  const Pose planetFrame = t.planet * Pose{Eigen::Matrix3d::Identity(), script_.planetCentre()};
  t.planetCentreCamera = planetFrame.t;
  if (frame >= 1) {
    Pose before, unused;
    poses(keyAt(frame - 1), before, unused);
    t.cameraStill =
        rotationAngle(before.R, t.camera.R) < 1e-9 && (before.t - t.camera.t).norm() < 1e-9;
  }
  t.tipPlanet = planetFrame.inverse().apply(t.tipCamera);
  t.tipHeight = t.tipPlanet.norm() - script_.planetRadius;
  if (script_.board || script_.toolLayout) {
    boardTruth(k, t);
    return t;
  }
  t.planetVisible = markerInView(t.planet, script_.planetMarkerSize, t.planetTiltDeg);
  t.toolVisible = markerInView(t.tool, script_.toolMarkerSize, t.toolTiltDeg);
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
  double half = 0.5 * script_.toolMarkerSize + (info.edgeOffset + toolMargin_) * cell;
  bool ok = !script_.toolLayout;  // a tool solid is drawn face by face (synth_bodies.cpp)
  for (const auto& c : {Eigen::Vector3d(-half, half, 0), Eigen::Vector3d(half, half, 0),
                        Eigen::Vector3d(half, -half, 0), Eigen::Vector3d(-half, -half, 0)}) {
    cv::Point2d px;
    ok = project(tool, c, px) && ok;
    o.toolCard.push_back(px);
  }
  if (!ok) o.toolCard.clear();
  // The stick, from the card's edge (or the solid's face) to the tip.
  const Eigen::Vector3d d = script_.tipOffset.normalized();
  if (script_.toolLayout) {
    const double grow = double(info.totalCells) / info.edgeCells;
    half = 0;
    for (const auto& m : script_.toolLayout->markers)
      for (const auto& c : m.corners)
        half = std::max(half, (m.inBody().t + grow * (c - m.inBody().t)).dot(d));
  }
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(d).normalized();
  // A tool solid's stick has its layout's radii (markers/tool-cube.json: 5 mm at the solid, 2 mm
  // at the tip), a single marker's 5 and 2 mm (tracking/tool_shape.cpp). Drawn as a flat strip
  // in the tool's x-y plane: the cone's outline as the camera sees the tool's face.
  const double w0 = script_.toolLayout ? script_.toolLayout->stickBaseRadius() : 0.005;
  const double w1 = script_.toolLayout ? script_.toolLayout->stickEndRadius() : 0.002;
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
  if (script_.board)
    drawBoard(img, cams);
  else
    drawTexturedQuadBlurred(img, planetCard_, hp, 8);

  const Overlays o = overlays(k, camera, tool);
  if (o.stickOk) {
    std::vector<cv::Point> poly;
    for (const auto& q : o.stick)
      poly.emplace_back(int(std::lround(q.x * 16)), int(std::lround(q.y * 16)));
    cv::fillConvexPoly(img, poly, cv::Scalar(40, 60, 90), cv::LINE_AA, 4);
  }
  if (script_.toolLayout)
    drawToolSolid(img, tools);
  else
    drawTexturedQuadBlurred(img, toolCard_, ht, 8);
  const auto hand = handPolygon(k, camera);
  if (!hand.empty()) {
    std::vector<cv::Point> poly;
    for (const auto& q : hand)
      poly.emplace_back(int(std::lround(q.x * 16)), int(std::lround(q.y * 16)));
    cv::fillPoly(img, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(110, 140, 190),
                 cv::LINE_AA, 4);
  }

  if (o.discRadius > 0.5)  // a hand over the planet marker's top-right corner
    cv::circle(img, cv::Point(int(std::lround(o.disc.x * 16)), int(std::lround(o.disc.y * 16))),
               int(std::lround(o.discRadius * 16)), cv::Scalar(110, 140, 190), cv::FILLED,
               cv::LINE_AA, 4);

  if (!distortMapX_.empty()) {
    cv::Mat lens;
    cv::remap(img, lens, distortMapX_, distortMapY_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    img = lens;
  }
  // The float frame and its noise kept per thread between frames: fresh multi-megabyte blocks
  // are fresh mappings whose pages fault in on first touch, every frame (under the sanitizers'
  // allocator a fifth of the tracking tests' time).
  thread_local cv::Mat f, noise;
  img.convertTo(f, CV_32F, k.gain);
  if (k.blur > 0.05) cv::GaussianBlur(f, f, cv::Size(0, 0), k.blur);
  if (k.noise > 0) {
    cv::RNG rng(script_.seed * 0x9E3779B97F4A7C15ULL + std::uint64_t(frame) * 7919ULL + 1);
    noise.create(f.size(), f.type());
    rng.fill(noise, cv::RNG::NORMAL, 0.0, k.noise);
    f += noise;
  }
  cv::Mat out;
  f.convertTo(out, CV_8U);
  if (!script_.colour) cv::cvtColor(out, out, cv::COLOR_BGR2GRAY);
  return out;
}

}  // namespace ps::tracking
