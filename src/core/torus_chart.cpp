#include "core/torus_chart.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::core {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// cos and sin of 2 pi k / m for k = 0 .. m, exact at the quarter turns and symmetric bit for
// bit: entry m - k is entry k with the sine negated (so entry m is entry 0).
void turnTables(int m, std::vector<double>& c, std::vector<double>& s) {
  c.assign(std::size_t(m) + 1, 0.0);
  s.assign(std::size_t(m) + 1, 0.0);
  for (int k = 0; 2 * k <= m; ++k) {
    double ck = std::cos(kTwoPi * k / m), sk = std::sin(kTwoPi * k / m);
    if (k == 0) ck = 1.0, sk = 0.0;
    if (4 * k == m) ck = 0.0, sk = 1.0;
    if (2 * k == m) ck = -1.0, sk = 0.0;
    c[std::size_t(k)] = c[std::size_t(m - k)] = ck;
    s[std::size_t(k)] = sk;
    s[std::size_t(m - k)] = -sk;
  }
  s[0] = s[std::size_t(m)] = 0.0;
  if (m % 2 == 0) s[std::size_t(m / 2)] = 0.0;
}

}  // namespace

TorusChart::TorusChart(GridSize grid, double majorRadius, double minorRadius)
    : Chart(grid), major_(majorRadius), minor_(minorRadius) {
  if (!std::isfinite(majorRadius) || !std::isfinite(minorRadius) || !(minorRadius > 0.0) ||
      !(minorRadius < majorRadius)) {
    throw InputError("torus radii: major " + std::to_string(majorRadius) + " m, minor " +
                     std::to_string(minorRadius) +
                     " m; both must be finite with 0 < minor < major (a ring torus)");
  }
  turnTables(grid.m(), cosU_, sinU_);
  turnTables(grid.m(), cosV_, sinV_);
}

int TorusChart::twins(int u, int v, GridPoint out[4]) const {
  const int m = grid().m();
  const int us[2] = {u, m - u}, vs[2] = {v, m - v};
  const int nu = (u == 0 || u == m) ? 2 : 1, nv = (v == 0 || v == m) ? 2 : 1;
  int n = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) out[n++] = {us[i], vs[j]};
  return n;
}

Eigen::Vector3d TorusChart::positionAt(double u, double v, double h) const {
  const double m = double(grid().m());
  const double alpha = kTwoPi * u / m, beta = kTwoPi * v / m;
  const double r = minor_ + h, rho = major_ + r * std::cos(beta);
  return {rho * std::cos(alpha), rho * std::sin(alpha), r * std::sin(beta)};
}

std::optional<Eigen::Vector2d> TorusChart::inverse(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) return std::nullopt;
  const double rho = std::hypot(p.x(), p.y());
  const double dr = rho - major_;
  if (!(rho > 0.0) || (dr == 0.0 && p.z() == 0.0)) return std::nullopt;
  const double m = double(grid().m());
  double u = std::atan2(p.y(), p.x()) / kTwoPi * m, v = std::atan2(p.z(), dr) / kTwoPi * m;
  if (u < 0) u += m;
  if (v < 0) v += m;
  return Eigen::Vector2d(std::clamp(u, 0.0, m), std::clamp(v, 0.0, m));
}

}  // namespace ps::core
