#include "core/octahedral_chart.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::core {

namespace {
constexpr double kPi = std::numbers::pi;
}

OctahedralChart::OctahedralChart(GridSize grid, double radius, Mapping mapping)
    : Chart(grid), radius_(radius), mapping_(mapping) {
  if (!std::isfinite(radius) || radius <= 0.0) {
    throw InputError("planet radius " + std::to_string(radius) + " m must be positive and finite");
  }
}

GridPoint OctahedralChart::canonical(int u, int v) const {
  const int m = grid().m();
  const bool uSide = u == 0 || u == m, vSide = v == 0 || v == m;
  if (uSide && vSide) return {0, 0};          // the four corners: the south pole
  if (vSide) return {std::min(u, m - u), v};  // (u, 0) is (m - u, 0); (u, m) likewise
  if (uSide) return {u, std::min(v, m - v)};  // (0, v) is (0, m - v); (m, v) likewise
  return {u, v};
}

int OctahedralChart::twins(int u, int v, GridPoint out[4]) const {
  const int m = grid().m();
  const bool uSide = u == 0 || u == m, vSide = v == 0 || v == m;
  if (uSide && vSide) {
    out[0] = {0, 0}, out[1] = {m, 0}, out[2] = {0, m}, out[3] = {m, m};
    return 4;
  }
  out[0] = {u, v};
  if (vSide && 2 * u != m) {
    out[1] = {m - u, v};
    return 2;
  }
  if (uSide && 2 * v != m) {
    out[1] = {u, m - v};
    return 2;
  }
  return 1;
}

Eigen::Vector3d OctahedralChart::directionOfSquare(double x, double y) const {
  const double ax = std::abs(x), ay = std::abs(y);
  const double sd = 1.0 - (ax + ay);  // >= 0: the northern hemisphere
  if (mapping_ == Mapping::kCentral) {
    // The octahedron |X| + |Y| + |Z| = 1, the southern faces folded out to the corners.
    const double X = sd >= 0 ? ax : 1.0 - ay, Y = sd >= 0 ? ay : 1.0 - ax;
    return Eigen::Vector3d(std::copysign(X, x), std::copysign(Y, y), sd).normalized();
  }
  // Equal area: r is the distance from the hemisphere's pole in the square's L1 sense, phi the
  // angle round it; z = 1 - r^2 keeps areas (Clarberg 2008).
  const double r = 1.0 - std::abs(sd);
  const double phi = r > 0 ? ((ay - ax) / r + 1.0) * (kPi / 4) : 0.0;
  const double s = r * std::sqrt(2.0 - r * r);
  return {std::copysign(std::cos(phi) * s, x), std::copysign(std::sin(phi) * s, y),
          std::copysign(1.0 - r * r, sd)};
}

Eigen::Vector3d OctahedralChart::direction(int u, int v) const {
  const GridPoint c = canonical(u, v);
  const double m = double(grid().m());
  return directionOfSquare(2.0 * c.u / m - 1.0, 2.0 * c.v / m - 1.0);
}

Eigen::Vector3d OctahedralChart::positionAt(double u, double v, double h) const {
  const double m = double(grid().m());
  return (radius_ + h) * directionOfSquare(2.0 * u / m - 1.0, 2.0 * v / m - 1.0);
}

std::optional<Eigen::Vector2d> OctahedralChart::inverse(const Eigen::Vector3d& p) const {
  const double norm = p.norm();
  if (!(norm > 0) || !std::isfinite(norm)) return std::nullopt;
  const Eigen::Vector3d n = p / norm;
  double ax, ay;
  if (mapping_ == Mapping::kCentral) {
    const Eigen::Vector3d q = n / n.cwiseAbs().sum();
    ax = q.z() >= 0 ? std::abs(q.x()) : 1.0 - std::abs(q.y());
    ay = q.z() >= 0 ? std::abs(q.y()) : 1.0 - std::abs(q.x());
  } else {
    const double r = std::sqrt(std::max(0.0, 1.0 - std::abs(n.z())));
    const double phi = std::atan2(std::abs(n.y()), std::abs(n.x()));  // [0, pi/2]
    const double along = 2.0 * r * phi / kPi;
    ax = n.z() >= 0 ? r - along : 1.0 - along;
    ay = n.z() >= 0 ? along : 1.0 - r + along;
  }
  const double m = double(grid().m());
  const double x = std::copysign(ax, n.x()), y = std::copysign(ay, n.y());
  return Eigen::Vector2d(std::clamp((x + 1.0) * 0.5 * m, 0.0, m),
                         std::clamp((y + 1.0) * 0.5 * m, 0.0, m));
}

}  // namespace ps::core
