#include "render/projection.hpp"

#include <algorithm>
#include <cmath>

#include "core/chart_factory.hpp"

namespace ps::render {

Eigen::Matrix4d clipFromCamera(const terrain::Camera& c, double n, double f) {
  const double W = c.width, H = c.height;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  // x_ndc = 2 (u + 0.5) / W - 1 and y_ndc = 1 - 2 (v + 0.5) / H for OpenCV pixel (u, v): GL's
  // pixel centres sit at +0.5 and its rows count upward.
  P(0, 0) = 2 * c.fx / W;
  P(0, 2) = 2 * (c.cx + 0.5) / W - 1;
  P(1, 1) = -2 * c.fy / H;
  P(1, 2) = 1 - 2 * (c.cy + 0.5) / H;
  P(2, 2) = (f + n) / (f - n);
  P(2, 3) = -2 * f * n / (f - n);
  P(3, 2) = 1;
  return P;
}

Eigen::Matrix4d clipFromEyeRelative(const Eigen::Matrix4d& clip, const Eigen::Matrix3d& rotation,
                                    const Eigen::Vector3d& offset) {
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.topLeftCorner<3, 3>() = rotation;
  view.topRightCorner<3, 1>() = rotation * offset;
  return clip * view;
}

std::optional<Eigen::Vector2d> pixelThroughFloatPath(const Eigen::Matrix4d& m,
                                                     const Eigen::Vector3f& p, int width,
                                                     int height) {
  const Eigen::Matrix4f mf = m.cast<float>();
  const Eigen::Vector4f c = mf * Eigen::Vector4f(p.x(), p.y(), p.z(), 1.0f);
  if (!(c.w() > 0)) return std::nullopt;
  // NDC -> OpenCV pixel: the inverse of clipFromCamera's mapping (kept in double: the
  // viewport transform is exact enough in the GPU's fixed-point rasteriser).
  const double x = double(c.x()) / double(c.w()), y = double(c.y()) / double(c.w());
  return Eigen::Vector2d(0.5 * (x + 1) * width - 0.5, 0.5 * (1 - y) * height - 0.5);
}

namespace {

// A torus or a cylinder (no sphere about the origin holds its surface at one radius): far at the
// far side of the sphere about the origin that holds every point of it, near at half the
// distance to that sphere, or, from inside it, at a quarter of the distance to the surface point
// under the eye (the chart's inverse), which no surface point is nearer than by more than the
// relief allows.
DepthRange tubeDepthRange(const terrain::Camera& camera, const terrain::Terrain& planet,
                          core::ChartShape shape) {
  const core::ChartDims dims = core::dimsOf(planet.chart());
  const double hi = std::max({0.0, double(planet.maxHeight()), -double(planet.minHeight())});
  const double outer = shape == core::ChartShape::kTorus
                           ? dims.radius + dims.minorRadius + hi
                           : std::hypot(dims.radius + hi, 0.5 * dims.length);
  const double d = camera.eye.norm();
  DepthRange r;
  r.farZ = d + outer;
  if (d > outer) {
    r.nearZ = 0.5 * (d - outer);
  } else if (const auto uv = planet.chart().inverse(camera.eye)) {
    const int side = planet.grid().side();
    const int u = std::clamp(int(std::lround((*uv)(0))), 0, side - 1);
    const int v = std::clamp(int(std::lround((*uv)(1))), 0, side - 1);
    const Eigen::Vector3d ground = planet.chart().position(u, v, planet.height(u, v));
    r.nearZ = 0.25 * std::max((camera.eye - ground).norm() - hi, 0.0);
  }
  r.nearZ = std::max({r.nearZ, r.farZ * 1e-7, 1e-3});
  r.farZ = std::max(r.farZ, 2 * r.nearZ);
  return r;
}

}  // namespace

DepthRange depthRangeFor(const terrain::Camera& camera, const terrain::Terrain& planet) {
  const core::ChartShape shape = core::shapeOf(planet.chart());
  if (shape == core::ChartShape::kTorus || shape == core::ChartShape::kCylinder)
    return tubeDepthRange(camera, planet, shape);
  const double R = planet.chart().sphereRadius();
  const double hi = std::max(0.0, double(planet.maxHeight()));
  const double lo = std::min(0.0, double(planet.minHeight()));
  const double shell = R + hi, core = R + lo;  // spheres holding all of the surface
  const double d = camera.eye.norm();
  DepthRange r;
  // Far: the farthest surface point in view is no farther than the tangent to the inner sphere
  // continued to the outer one (beyond it the planet hides itself).
  r.farZ = d + shell;
  if (d > core) {
    r.farZ =
        std::min(r.farZ, std::sqrt(d * d - core * core) + std::sqrt(shell * shell - core * core));
  }
  if (d > shell) {
    r.nearZ = 0.5 * (d - shell);
  } else {
    // Inside the relief's shell: the surface can be as near as the ground under the camera (or
    // a slope beside it); a quarter of the altitude above the ground is a safe near plane.
    double ground = R;
    if (const auto uv = planet.chart().inverse(camera.eye)) {
      const int side = planet.grid().side();
      const int u = std::clamp(int(std::lround((*uv)(0))), 0, side - 1);
      const int v = std::clamp(int(std::lround((*uv)(1))), 0, side - 1);
      ground += planet.height(u, v);
    }
    r.nearZ = 0.25 * std::max(d - ground, 0.0);
  }
  r.nearZ = std::max({r.nearZ, r.farZ * 1e-7, 1e-3});
  r.farZ = std::max(r.farZ, 2 * r.nearZ);
  return r;
}

terrain::Camera arCamera(const Eigen::Matrix3d& Rcp, const Eigen::Vector3d& tcp, double scale,
                         const Eigen::Matrix3d& K, int width, int height) {
  terrain::Camera c;
  c.rotation = Rcp;
  // Camera centre in the planet frame: -R^T t, in planet metres.
  c.eye = -(Rcp.transpose() * tcp) * scale;
  c.fx = K(0, 0);
  c.fy = K(1, 1);
  c.cx = K(0, 2);
  c.cy = K(1, 2);
  c.width = width;
  c.height = height;
  return c;
}

}  // namespace ps::render
