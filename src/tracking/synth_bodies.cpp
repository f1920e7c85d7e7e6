// Synthetic video of rigid marker sets (synth.hpp): the planet board on its white sheet, the tool
// solid (a box whose faces carry the layout's markers) on its stick, a hand held over the table,
// and the ground truth of what each marker shows of itself.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "tracking/synth.hpp"
#include "tracking/synth_internal.hpp"
#include "tracking/textured_quad.hpp"
#include "tracking/tool_shape.hpp"

namespace ps::tracking {

using namespace synth_detail;

namespace {

// A face of the tool's box: its frame (x, y in the face, z = x × y outward) and half sizes.
struct BoxFace {
  Pose frame;
  double halfX = 0, halfY = 0;
  const LayoutMarker* marker = nullptr;  // the marker printed on it, if any
};

// The box that holds the layout's markers with their quiet zones: the printed solid.
std::vector<BoxFace> solidFaces(const MarkerLayout& layout, const FamilyInfo& info) {
  const auto [lo, hi] = markersBox(layout, double(info.totalCells) / info.edgeCells);
  const Eigen::Vector3d mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  std::vector<BoxFace> faces;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  // (outward normal axis, sign, face x, face y) with x × y = the outward normal.
  const struct {
    int axis;
    double sign;
    Eigen::Vector3d x, y;
  } spec[] = {{2, 1, X, Y},  {2, -1, -X, Y}, {0, 1, -Z, Y},
              {0, -1, Z, Y}, {1, 1, X, -Z},  {1, -1, X, Z}};
  for (const auto& f : spec) {
    BoxFace b;
    b.frame.R.col(0) = f.x;
    b.frame.R.col(1) = f.y;
    b.frame.R.col(2) = f.x.cross(f.y);
    b.frame.t = mid;
    b.frame.t[f.axis] += f.sign * half[f.axis];
    b.halfX = std::abs(f.x.dot(half));
    b.halfY = std::abs(f.y.dot(half));
    for (const auto& m : layout.markers) {
      const Pose p = m.inBody();
      if (p.R.col(2).dot(b.frame.R.col(2)) > 0.99 &&
          std::abs((p.t - b.frame.t).dot(b.frame.R.col(2))) < 1e-3)
        b.marker = &m;
    }
    faces.push_back(b);
  }
  return faces;
}

bool facesCamera(const Pose& inCamera) {
  return inCamera.R.col(2).dot(-inCamera.t) > 0;
}

// A uniform grey texture's texels (0..2) onto a face rectangle of half sizes hx, hy.
cv::Matx33d plainToPlane(double hx, double hy) {
  return {hx, 0, -hx, 0, -hy, hy, 0, 0, 1};
}

cv::Mat plain(int grey) {
  return cv::Mat(2, 2, CV_8U, cv::Scalar(grey));
}

bool projectAll(const CameraCalibration& cam, const std::vector<Eigen::Vector3d>& camPoints,
                std::vector<cv::Point2d>& out) {
  out.clear();
  for (const auto& x : camPoints) {
    if (x.z() <= 1e-3) return false;
    out.emplace_back(cam.K(0, 0) * x.x() / x.z() + cam.K(0, 2),
                     cam.K(1, 1) * x.y() / x.z() + cam.K(1, 2));
  }
  return true;
}

// Fraction of a marker's face (a 5 x 5 grid of points over it) that is in the image and not
// under any of `covers`.
double visibleFraction(const Pose& marker, double edge, const CameraCalibration& cam, cv::Size size,
                       const std::vector<std::vector<cv::Point2d>>& covers) {
  if (!facesCamera(marker)) return 0;
  int seen = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      const Eigen::Vector3d x =
          marker.apply({((i + 0.5) / 5 - 0.5) * edge, ((j + 0.5) / 5 - 0.5) * edge, 0});
      if (x.z() <= 1e-3) continue;
      const cv::Point2d p(cam.K(0, 0) * x.x() / x.z() + cam.K(0, 2),
                          cam.K(1, 1) * x.y() / x.z() + cam.K(1, 2));
      if (p.x < 2 || p.y < 2 || p.x > size.width - 3 || p.y > size.height - 3) continue;
      bool covered = false;
      for (const auto& c : covers) {
        if (c.size() < 3) continue;
        std::vector<cv::Point2f> f(c.begin(), c.end());
        covered |= cv::pointPolygonTest(f, cv::Point2f(p), false) >= 0;
        if (covered) break;
      }
      seen += covered ? 0 : 1;
    }
  return seen / 25.0;
}

}  // namespace

cv::Mat handInFrontOfPlanet(const SynthScript& s, const SynthKey& k, const Pose& camera) {
  cv::Mat out = cv::Mat::zeros(s.size, CV_8U);
  if (!(k.handRadius > 0)) return out;
  const Eigen::Vector3d C = camera.inverse().t, S = s.planetCentre();
  const cv::Matx33d& K = s.camera.K;
  for (int v = 0; v < s.size.height; ++v)
    for (int u = 0; u < s.size.width; ++u) {
      const Eigen::Vector3d d =
          camera.R.transpose() *
          Eigen::Vector3d((u - K(0, 2)) / K(0, 0), (v - K(1, 2)) / K(1, 1), 1.0).normalized();
      const Eigen::Vector3d oc = C - S;
      const double b = oc.dot(d), c = oc.squaredNorm() - s.planetRadius * s.planetRadius;
      if (b * b - c < 0 || -b <= 0) continue;  // misses the sphere
      const double tSphere = -b - std::sqrt(b * b - c);
      if (std::abs(d.z()) < 1e-9) continue;
      const double tHand = (k.handHeight - C.z()) / d.z();
      if (!(tHand > 0) || tHand >= tSphere) continue;
      const Eigen::Vector3d p = C + tHand * d;
      if (std::hypot(p.x() - k.handX, p.y() - k.handY) <= k.handRadius) out.at<uchar>(v, u) = 255;
    }
  return out;
}

std::vector<cv::Point2d> SynthRenderer::handPolygon(const SynthKey& k, const Pose& camera) const {
  if (!(k.handRadius > 0)) return {};
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 48; ++i) {
    const double a = 2 * std::numbers::pi * i / 48;
    pts.push_back(camera.apply({k.handX + k.handRadius * std::cos(a),
                                k.handY + k.handRadius * std::sin(a), k.handHeight}));
  }
  std::vector<cv::Point2d> px;
  if (!projectAll(script_.camera, pts, px)) return {};
  return px;
}

std::vector<std::vector<cv::Point2d>> SynthRenderer::occluders(const SynthKey& k,
                                                               const Pose& camera,
                                                               const Pose& tool) const {
  std::vector<std::vector<cv::Point2d>> out;
  const Overlays o = overlays(k, camera, tool);
  if (script_.toolLayout) {
    for (const auto& f : solidFaces(*script_.toolLayout, familyInfo(script_.toolLayout->family))) {
      const Pose p = tool * f.frame;
      if (!facesCamera(p)) continue;
      std::vector<cv::Point2d> px;
      if (projectAll(script_.camera,
                     {p.apply({-f.halfX, f.halfY, 0}), p.apply({f.halfX, f.halfY, 0}),
                      p.apply({f.halfX, -f.halfY, 0}), p.apply({-f.halfX, -f.halfY, 0})},
                     px))
        out.push_back(px);
    }
  } else if (!o.toolCard.empty()) {
    out.push_back(o.toolCard);
  }
  if (o.stickOk) out.push_back(o.stick);
  const auto hand = handPolygon(k, camera);
  if (!hand.empty()) out.push_back(hand);
  return out;
}

void SynthRenderer::drawBoard(cv::Mat& img, const std::vector<Pose>& cams) const {
  const MarkerLayout& board = *script_.board;
  const FamilyInfo info = familyInfo(board.family);
  // The white sheet: the markers' extent and a 15 mm margin, on the table.
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (const auto& m : board.markers)
    for (const auto& c : m.corners) {
      x0 = std::min(x0, c.x()), x1 = std::max(x1, c.x());
      y0 = std::min(y0, c.y()), y1 = std::max(y1, c.y());
    }
  const double margin = 0.015;
  Pose sheet;
  sheet.t = {0.5 * (x0 + x1), 0.5 * (y0 + y1), 0};
  const double hx = 0.5 * (x1 - x0) + margin, hy = 0.5 * (y1 - y0) + margin;
  std::vector<cv::Matx33d> hs;
  for (const auto& c : cams)
    hs.push_back(planeHomography(script_.camera, c * sheet) * plainToPlane(hx, hy));
  drawTexturedQuadBlurred(img, plain(232), hs, 4);
  for (std::size_t i = 0; i < board.markers.size(); ++i) {
    const LayoutMarker& m = board.markers[i];
    std::vector<cv::Matx33d> h;
    for (const auto& c : cams)
      h.push_back(planeHomography(script_.camera, c * m.inBody()) * cardToPlane(info, 0, m.edge()));
    drawTexturedQuadBlurred(img, boardCards_[i], h, 8);
  }
}

void SynthRenderer::drawToolSolid(cv::Mat& img, const std::vector<Pose>& tools) const {
  const MarkerLayout& layout = *script_.toolLayout;
  const FamilyInfo info = familyInfo(layout.family);
  const Pose& mid = tools[tools.size() / 2];
  for (const auto& f : solidFaces(layout, info)) {
    if (!facesCamera(mid * f.frame)) continue;  // a convex solid: front faces never overlap
    std::vector<cv::Matx33d> h;
    if (f.marker) {
      const auto index = std::size_t(f.marker - layout.markers.data());
      for (const auto& t : tools)
        h.push_back(planeHomography(script_.camera, t * f.marker->inBody()) *
                    cardToPlane(info, 0, f.marker->edge()));
      drawTexturedQuadBlurred(img, toolFaceCards_[index], h, 8);
    } else {
      for (const auto& t : tools)
        h.push_back(planeHomography(script_.camera, t * f.frame) * plainToPlane(f.halfX, f.halfY));
      drawTexturedQuadBlurred(img, plain(95), h, 8);
    }
  }
}

void SynthRenderer::boardTruth(const SynthKey& k, FrameTruth& t) const {
  const auto covers = occluders(k, t.camera, t.tool);
  const auto hand = handPolygon(k, t.camera);
  std::vector<std::vector<cv::Point2d>> handOnly;
  if (!hand.empty()) handOnly.push_back(hand);
  const MarkerLayout planet =
      script_.board ? *script_.board
                    : MarkerLayout::singleMarker(script_.planetId, script_.planetMarkerSize);
  const MarkerLayout tool =
      script_.toolLayout ? *script_.toolLayout
                         : MarkerLayout::singleMarker(script_.toolId, script_.toolMarkerSize);
  t.planetVisible = t.planetOccluded = false;
  t.planetTiltDeg = 90;
  for (const auto& m : planet.markers) {
    const Pose p = t.planet * m.inBody();
    double tilt = 0;
    const bool inView = markerInView(p, m.edge(), tilt);
    t.planetTiltDeg = std::min(t.planetTiltDeg, tilt);
    const double seen = visibleFraction(p, m.edge(), script_.camera, script_.size, covers);
    const double inImage = visibleFraction(p, m.edge(), script_.camera, script_.size, {});
    t.boardVisible.emplace_back(m.id, seen);
    t.boardHalfVisible += seen >= 0.5 ? 1 : 0;
    t.planetVisible |= inView && seen >= 1.0;
    t.planetOccluded |= seen < inImage;
  }
  t.toolVisible = t.toolOccluded = false;
  t.toolTiltDeg = 90;
  for (const auto& m : tool.markers) {
    const Pose p = t.tool * m.inBody();
    double tilt = 0;
    if (!markerInView(p, m.edge(), tilt)) continue;
    t.toolTiltDeg = std::min(t.toolTiltDeg, tilt);
    const bool clear = visibleFraction(p, m.edge(), script_.camera, script_.size, handOnly) >= 1.0;
    t.toolVisible |= clear;
    t.toolOccluded |= !clear;
  }
}

}  // namespace ps::tracking
