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

namespace {

// sin and cos of (pi/2) t for t in [0, 1], without a libm call: the angle is folded to [0, pi/4]
// (exactly: 1 - t is exact for t in [0.5, 1]) and evaluated by Cephes' minimax polynomials
// (relative error about 1e-16). The grid vertices of one point reach it with the same t (their
// canonical vertex's), so they get the same bits.
inline void quarterTurnSinCos(double t, double& sine, double& cosine) {
  const bool swap = t > 0.5;
  const double x = (swap ? 1.0 - t : t) * (std::numbers::pi / 2), z = x * x;
  const double s = x + x * z *
                           (((((1.58962301576546568060e-10 * z - 2.50507477628578072866e-8) * z +
                               2.75573136213857245213e-6) *
                                  z -
                              1.98412698295895385996e-4) *
                                 z +
                             8.33333333332211858878e-3) *
                                z -
                            1.66666666666666307295e-1);
  const double c = 1.0 - 0.5 * z +
                   z * z *
                       (((((-1.13585365213876817300e-11 * z + 2.08757008419747316778e-9) * z -
                           2.75573141792967388112e-7) *
                              z +
                          2.48015872888517045348e-5) *
                             z -
                         1.38888888888730564116e-3) *
                            z +
                        4.16666666666665929218e-2);
  sine = swap ? c : s;
  cosine = swap ? s : c;
}

}  // namespace

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
  // phi = ((ay - ax) / r + 1) pi/4 = t pi/2 with t = ay / r in the north (r = ax + ay) and
  // (1 - ax) / r in the south (r = 2 - ax - ay).
  const double r = 1.0 - std::abs(sd);
  const double t = r > 0 ? (sd >= 0 ? ay : 1.0 - ax) / r : 0.0;
  double sine, cosine;
  quarterTurnSinCos(std::clamp(t, 0.0, 1.0), sine, cosine);
  const double s = r * std::sqrt(2.0 - r * r);
  return {std::copysign(cosine * s, x), std::copysign(sine * s, y), std::copysign(1.0 - r * r, sd)};
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
