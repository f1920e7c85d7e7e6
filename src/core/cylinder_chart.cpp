#include "core/cylinder_chart.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::core {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}

CylinderChart::CylinderChart(GridSize grid, double radius, double length)
    : Chart(grid), radius_(radius), length_(length) {
  if (!std::isfinite(radius) || !std::isfinite(length) || !(radius > 0.0) || !(length > 0.0)) {
    throw InputError("cylinder radius " + std::to_string(radius) + " m and length " +
                     std::to_string(length) + " m must be positive and finite");
  }
  const int m = grid.m();
  cosU_.assign(std::size_t(m) + 1, 0.0);
  sinU_.assign(std::size_t(m) + 1, 0.0);
  z_.assign(std::size_t(m) + 1, 0.0);
  // Entry m is entry 0 (seam twins one point bit for bit), exact at the quarter turns.
  for (int k = 0; k < m; ++k) {
    double c = std::cos(kTwoPi * k / m), s = std::sin(kTwoPi * k / m);
    if (k == 0) c = 1.0, s = 0.0;
    if (4 * k == m) c = 0.0, s = 1.0;
    if (2 * k == m) c = -1.0, s = 0.0;
    if (4 * k == 3 * m) c = 0.0, s = -1.0;
    cosU_[std::size_t(k)] = c, sinU_[std::size_t(k)] = s;
  }
  cosU_[std::size_t(m)] = cosU_[0], sinU_[std::size_t(m)] = sinU_[0];
  for (int k = 0; k <= m; ++k) z_[std::size_t(k)] = length * (double(k) / m - 0.5);
}

Eigen::Vector3d CylinderChart::positionAt(double u, double v, double h) const {
  const double m = double(grid().m()), alpha = kTwoPi * u / m, r = radius_ + h;
  return {r * std::cos(alpha), r * std::sin(alpha), length_ * (v / m - 0.5)};
}

std::optional<Eigen::Vector2d> CylinderChart::inverse(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) return std::nullopt;
  const double rho = std::hypot(p.x(), p.y());
  if (!(rho > 0.0)) return std::nullopt;
  const double m = double(grid().m());
  double u = std::atan2(p.y(), p.x()) / kTwoPi * m;
  if (u < 0) u += m;
  const double v = (p.z() / length_ + 0.5) * m;
  return Eigen::Vector2d(std::clamp(u, 0.0, m), std::clamp(v, 0.0, m));
}

}  // namespace ps::core
