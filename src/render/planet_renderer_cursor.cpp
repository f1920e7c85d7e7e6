// The tool's cursor drawn over the planet: a ring at the radius of deformation around the
// control vertex, a cross at it, and (on a sphere) the haptic force as an arrow.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "render/planet_renderer.hpp"

namespace ps::render {

void PlanetRenderer::drawCursor(const terrain::Terrain& planet, const Cursor& cursor,
                                const terrain::Camera& camera, const Eigen::Matrix4d& clip) {
  if (!(planet.chart().sphereRadius() > 0)) {
    drawSurfaceCursor(planet, cursor, camera, clip);
    return;
  }
  // A ring at geodesic distance r_d around the control vertex, lifted 0.2 % of r_d so that
  // it stays above the facets, and a cross at the control vertex.
  const core::Chart& chart = planet.chart();
  const Eigen::Vector3d n = chart.up(cursor.control.u, cursor.control.v);
  const double R = chart.sphereRadius();
  const double h = planet.height(cursor.control.u, cursor.control.v);
  Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  const double angle = cursor.radius / R;
  std::vector<Eigen::Vector3d> ring;
  for (int i = 0; i < 96; ++i) {
    const double phi = 2 * std::numbers::pi * i / 96;
    const Eigen::Vector3d dir =
        (std::cos(angle) * n + std::sin(angle) * (std::cos(phi) * e1 + std::sin(phi) * e2));
    ring.push_back(dir * (R + h + 0.002 * cursor.radius));
  }
  drawLines(ring, true, camera, clip, {1.0f, 0.85f, 0.1f}, false);
  const Eigen::Vector3d c = n * (R + h);
  const double arm = 0.15 * cursor.radius;
  drawLines({c - arm * e1, c + arm * e1, c - arm * e2, c + arm * e2}, false, camera, clip,
            {1.0f, 0.2f, 0.1f}, false);
  if (cursor.arrow.norm() > 0 && cursor.arrowFrom.allFinite() && cursor.arrow.allFinite()) {
    // Shaft and a two-stroke head in the plane of the shaft and the view direction.
    const Eigen::Vector3d a = cursor.arrowFrom, b = a + cursor.arrow;
    const Eigen::Vector3d dir = cursor.arrow.normalized();
    Eigen::Vector3d side = dir.cross(b - camera.eye);
    side = side.norm() > 0 ? side.normalized() : dir.unitOrthogonal();
    const double head = 0.25 * cursor.arrow.norm();
    drawLines({a, b, b, b - head * dir + 0.5 * head * side, b, b - head * dir - 0.5 * head * side},
              false, camera, clip, {0.2f, 1.0f, 0.3f}, false);
  }
}

void PlanetRenderer::drawSurfaceCursor(const terrain::Terrain& planet, const Cursor& cursor,
                                       const terrain::Camera& camera, const Eigen::Matrix4d& clip) {
  const core::Chart& chart = planet.chart();
  const int side = planet.grid().side();
  const Eigen::Vector3d n = chart.up(cursor.control.u, cursor.control.v);
  const Eigen::Vector3d c = chart.position(cursor.control.u, cursor.control.v,
                                           planet.height(cursor.control.u, cursor.control.v));
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  const double lift = 0.002 * cursor.radius;
  // A point of the tangent plane laid onto the surface under it (the nearest vertex's height).
  auto onSurface = [&](const Eigen::Vector3d& q) -> std::optional<Eigen::Vector3d> {
    const auto uv = chart.inverse(q);
    if (!uv) return std::nullopt;
    const int u = std::clamp(int(std::lround(uv->x())), 0, side - 1);
    const int v = std::clamp(int(std::lround(uv->y())), 0, side - 1);
    return chart.positionAt(uv->x(), uv->y(), planet.height(u, v) + lift);
  };
  std::vector<Eigen::Vector3d> ring;
  for (int i = 0; i < 96; ++i) {
    const double phi = 2 * std::numbers::pi * i / 96;
    if (auto p = onSurface(c + cursor.radius * (std::cos(phi) * e1 + std::sin(phi) * e2)))
      ring.push_back(*p);
  }
  if (ring.size() == 96) drawLines(ring, true, camera, clip, {1.0f, 0.85f, 0.1f}, false);
  const double arm = 0.15 * cursor.radius;
  drawLines({c - arm * e1, c + arm * e1, c - arm * e2, c + arm * e2}, false, camera, clip,
            {1.0f, 0.2f, 0.1f}, false);
}

}  // namespace ps::render
