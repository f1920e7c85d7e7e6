#include "tracking/tool_shape.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "tracking/marker_family.hpp"

namespace ps::tracking {

namespace {

// The single tool marker's card and stick (synth.cpp draws them so; markers/README.md).
constexpr double kCardMarginCells = 2, kCardHalfThickness = 0.0005;
constexpr double kSingleStickBase = 0.005, kSingleStickTip = 0.002;

// The convex hull (pixels) of body points seen by the camera; empty when one lies behind it.
std::vector<cv::Point2f> silhouette(const std::vector<Eigen::Vector3d>& body, const Pose& tool,
                                    const CameraCalibration& calib) {
  std::vector<cv::Point3f> inCamera;
  for (const auto& p : body) {
    const Eigen::Vector3d x = tool.apply(p);
    if (!(x.z() > 1e-3)) return {};
    inCamera.emplace_back(float(x.x()), float(x.y()), float(x.z()));
  }
  std::vector<cv::Point2f> px, hull;
  cv::projectPoints(inCamera, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calib.K),
                    calib.distortion, px);
  cv::convexHull(px, hull);
  return hull;
}

}  // namespace

MarkerBox markersBox(const MarkerLayout& layout, double grow) {
  MarkerBox box{Eigen::Vector3d::Constant(1e9), Eigen::Vector3d::Constant(-1e9)};
  for (const auto& m : layout.markers) {
    const Eigen::Vector3d c = m.inBody().t;
    for (const auto& p : m.corners) {
      const Eigen::Vector3d q = c + grow * (p - c);
      box.lo = box.lo.cwiseMin(q);
      box.hi = box.hi.cwiseMax(q);
    }
  }
  return box;
}

ToolShape toolShape(const MarkerLayout& layout, const Eigen::Vector3d& tip, double marginCells) {
  const FamilyInfo info = familyInfo(layout.family);
  const auto [lo, hi] = markersBox(layout, (info.totalCells + 2 * marginCells) / info.edgeCells);
  ToolShape s;
  s.boxCentre = 0.5 * (lo + hi);
  s.boxHalf = (0.5 * (hi - lo)).cwiseMax(kCardHalfThickness);  // a flat card has a thickness
  s.tip = tip;
  s.baseRadius = layout.stickBaseRadius();
  s.tipRadius = layout.stickEndRadius();
  // The stick leaves the solid where the line from the body's origin to the tip crosses the
  // box's surface (synth draws it from there).
  const Eigen::Vector3d d = tip.normalized();
  double leave = tip.norm();
  for (int i = 0; i < 3; ++i)
    if (std::abs(d[i]) > 1e-12) leave = std::min(leave, std::max(lo[i] / d[i], hi[i] / d[i]));
  s.stickBase = std::max(leave, 0.0) * d;
  return s;
}

ToolShape toolShape(const SceneConfig& scene, const std::string& family) {
  if (scene.tool.layout) return toolShape(*scene.tool.layout, scene.tipOffset);
  const MarkerLayout card = MarkerLayout::singleMarker(scene.tool.id, scene.tool.size, family);
  ToolShape s = toolShape(card, scene.tipOffset, kCardMarginCells);
  s.baseRadius = kSingleStickBase;
  s.tipRadius = kSingleStickTip;
  return s;
}

std::vector<Eigen::Vector3d> toolTriangles(const ToolShape& shape, const Pose& bodyToTarget,
                                           double scale, int segments) {
  std::vector<Eigen::Vector3d> out;
  auto put = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    for (const auto* p : {&a, &b, &c}) out.push_back(scale * bodyToTarget.apply(*p));
  };
  // The box: corner k has bit i set where it lies at +half along axis i.
  auto corner = [&](int k) {
    Eigen::Vector3d p = shape.boxCentre;
    for (int i = 0; i < 3; ++i) p[i] += ((k >> i) & 1 ? 1 : -1) * shape.boxHalf[i];
    return p;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3, base = side << axis;
      const Eigen::Vector3d p00 = corner(base), p10 = corner(base | 1 << u),
                            p11 = corner(base | 1 << u | 1 << v), p01 = corner(base | 1 << v);
      put(p00, p10, p11);
      put(p00, p11, p01);
    }
  if (!shape.hasStick()) return out;
  // The cone: rings at the base and the tip about the stick's axis.
  const Eigen::Vector3d axis = (shape.tip - shape.stickBase).normalized();
  const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  const int n = std::max(segments, 3);
  auto ring = [&](const Eigen::Vector3d& centre, double r, int k) {
    const double a = 2 * std::numbers::pi * k / n;
    return Eigen::Vector3d(centre + r * (std::cos(a) * e1 + std::sin(a) * e2));
  };
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d b0 = ring(shape.stickBase, shape.baseRadius, k),
                          b1 = ring(shape.stickBase, shape.baseRadius, k + 1),
                          t0 = ring(shape.tip, shape.tipRadius, k),
                          t1 = ring(shape.tip, shape.tipRadius, k + 1);
    put(b0, b1, t1);
    put(b0, t1, t0);
    put(shape.stickBase, b1, b0);
    put(shape.tip, t0, t1);
  }
  return out;
}

bool toolCoversMarkerOutline(const ToolShape& shape, const Pose& tool,
                             const CameraCalibration& calib,
                             const std::array<cv::Point2d, 4>& corners, int edgeCells,
                             double bandCells) {
  std::vector<Eigen::Vector3d> box, stick;
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector3d p = shape.boxCentre;
    for (int i = 0; i < 3; ++i) p[i] += ((k >> i) & 1 ? 1 : -1) * shape.boxHalf[i];
    box.push_back(p);
  }
  if (shape.hasStick()) {
    // The cone's two end rings, eight points each: their hull holds the cone's outline.
    const Eigen::Vector3d axis = (shape.tip - shape.stickBase).normalized();
    const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
    for (int k = 0; k < 8; ++k) {
      const double a = std::numbers::pi * k / 4;
      const Eigen::Vector3d r = std::cos(a) * e1 + std::sin(a) * e2;
      // The ring's chords lie inside the circle: grown so the octagon holds it.
      const double grow = 1 / std::cos(std::numbers::pi / 8);
      stick.push_back(shape.stickBase + grow * shape.baseRadius * r);
      stick.push_back(shape.tip + grow * shape.tipRadius * r);
    }
  }
  double perimeter = 0;
  for (int k = 0; k < 4; ++k) perimeter += cv::norm(corners[k] - corners[(k + 1) % 4]);
  const double band = bandCells * perimeter / (4.0 * edgeCells);
  for (const auto& body : {box, stick}) {
    if (body.empty()) continue;
    const std::vector<cv::Point2f> hull = silhouette(body, tool, calib);
    if (hull.size() < 3) continue;
    for (int k = 0; k < 4; ++k) {
      // The band about edge k: band wide on either side, band beyond either end.
      const cv::Point2d a = corners[k], b = corners[(k + 1) % 4];
      const double len = cv::norm(b - a);
      if (!(len > 0)) continue;
      const cv::Point2d u = (b - a) / len, n(-u.y, u.x);
      const std::vector<cv::Point2f> strip = {
          cv::Point2f(a - band * u - band * n), cv::Point2f(b + band * u - band * n),
          cv::Point2f(b + band * u + band * n), cv::Point2f(a - band * u + band * n)};
      std::vector<cv::Point2f> overlap;
      if (cv::intersectConvexConvex(hull, strip, overlap) > 0) return true;
    }
  }
  return false;
}

}  // namespace ps::tracking
