#include "core/octahedral_chart.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::core {

namespace {
constexpr double kPi = std::numbers::pi;

// canonical() without branches (the scattered positions' loop vectorises with it): the four
// corners are (0, 0); (u, 0) is (m - u, 0) and (u, m) is (m - u, m), the one with the smaller u;
// (0, v) and (m, v) likewise in v.
inline void canonicalOf(int m, int u, int v, int& cu, int& cv) {
  const bool uSide = (u == 0) | (u == m), vSide = (v == 0) | (v == m);
  const int uMirror = m - u < u ? m - u : u, vMirror = m - v < v ? m - v : v;
  cu = vSide ? (uSide ? 0 : uMirror) : u;
  cv = uSide ? (vSide ? 0 : vMirror) : v;
}

// Square coordinate 2 i / m - 1 of grid index i: m is a power of two, so multiplying by 1 / m
// is the division, bit for bit, without one.
inline double squareCoordinate(int i, double invM) {
  return 2.0 * double(i) * invM - 1.0;
}
}  // namespace

OctahedralChart::OctahedralChart(GridSize grid, double radius, Mapping mapping)
    : Chart(grid), radius_(radius), mapping_(mapping) {
  if (!std::isfinite(radius) || radius <= 0.0) {
    throw InputError("planet radius " + std::to_string(radius) + " m must be positive and finite");
  }
}

GridPoint OctahedralChart::canonical(int u, int v) const {
  GridPoint c;
  canonicalOf(grid().m(), u, v, c.u, c.v);
  return c;
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

// The equal-area direction of square coordinates (x, y) (Clarberg 2008): r is the distance
// from the hemisphere's pole in the square's L1 sense, phi the angle round it; z = 1 - r^2
// keeps areas. phi = ((ay - ax) / r + 1) pi/4 = t pi/2 with t = ay / r in the north
// (r = ax + ay) and (1 - ax) / r in the south (r = 2 - ax - ay). Without branches, so that the
// row and scattered loops vectorise; every path computes a direction with this one function.
inline void equalAreaDirection(double x, double y, double& dx, double& dy, double& dz) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double sd = 1.0 - (ax + ay);  // >= 0: the northern hemisphere
  const double r = 1.0 - std::abs(sd);
  // At the pole (r = 0) the quotient is dropped: divided by 1 there, so that the division is
  // no branch.
  const double q = (sd >= 0 ? ay : 1.0 - ax) / (r > 0 ? r : 1.0);
  const double t = r > 0 ? q : 0.0;
  double sine, cosine;
  quarterTurnSinCos(std::clamp(t, 0.0, 1.0), sine, cosine);
  const double s = r * std::sqrt(2.0 - r * r);
  dx = std::copysign(cosine * s, x);
  dy = std::copysign(sine * s, y);
  dz = std::copysign(1.0 - r * r, sd);
}

}  // namespace

Eigen::Vector3d OctahedralChart::directionOfSquare(double x, double y) const {
  if (mapping_ == Mapping::kCentral) {
    // The octahedron |X| + |Y| + |Z| = 1, the southern faces folded out to the corners.
    const double ax = std::abs(x), ay = std::abs(y);
    const double sd = 1.0 - (ax + ay);  // >= 0: the northern hemisphere
    const double X = sd >= 0 ? ax : 1.0 - ay, Y = sd >= 0 ? ay : 1.0 - ax;
    return Eigen::Vector3d(std::copysign(X, x), std::copysign(Y, y), sd).normalized();
  }
  Eigen::Vector3d d;
  equalAreaDirection(x, y, d.x(), d.y(), d.z());
  return d;
}

Eigen::Vector3d OctahedralChart::direction(int u, int v) const {
  const int m = grid().m();
  const double invM = 1.0 / double(m);
  int cu, cv;
  canonicalOf(m, u, v, cu, cv);
  return directionOfSquare(squareCoordinate(cu, invM), squareCoordinate(cv, invM));
}

namespace {

// Row v's interior vertices uFirst .. uFirst + n - 1 (0 < u < m, 0 < v < m: each its own
// canonical vertex): position()'s arithmetic, in its order.
__attribute__((target_clones("avx512f", "avx2", "default"))) void equalAreaRow(
    double y, double invM, double r0, int uFirst, int n, const float* __restrict h,
    double* __restrict x, double* __restrict yOut, double* __restrict z) {
  for (int k = 0; k < n; ++k) {
    double dx, dy, dz;
    equalAreaDirection(squareCoordinate(uFirst + k, invM), y, dx, dy, dz);
    const double r = r0 + double(h[k]);
    x[k] = r * dx, yOut[k] = r * dy, z[k] = r * dz;
  }
}

// Any grid vertices, each at its canonical vertex: position()'s arithmetic, in its order.
__attribute__((target_clones("avx512f", "avx2", "default"))) void equalAreaScattered(
    int m, double invM, double r0, const std::int32_t* __restrict u,
    const std::int32_t* __restrict v, const float* __restrict h, std::size_t n,
    double* __restrict x, double* __restrict y, double* __restrict z) {
  for (std::size_t k = 0; k < n; ++k) {
    int cu, cv;
    canonicalOf(m, u[k], v[k], cu, cv);
    double dx, dy, dz;
    equalAreaDirection(squareCoordinate(cu, invM), squareCoordinate(cv, invM), dx, dy, dz);
    const double r = r0 + double(h[k]);
    x[k] = r * dx, y[k] = r * dy, z[k] = r * dz;
  }
}

}  // namespace

void OctahedralChart::rowPositions(int v, int uFirst, int uLast, const float* hRow,
                                   RowOut out) const {
  const int m = grid().m();
  auto one = [&](int u) {
    const Eigen::Vector3d p = position(u, v, double(hRow[u]));
    const int k = u - uFirst;
    out.x[k] = p.x(), out.y[k] = p.y(), out.z[k] = p.z();
  };
  if (mapping_ != Mapping::kEqualArea || v == 0 || v == m) {
    for (int u = uFirst; u <= uLast; ++u) one(u);
    return;
  }
  // The side columns' canonical vertices lie in row m - v: position() takes them.
  int a = uFirst, b = uLast;
  if (a == 0) one(a++);
  if (b == m && b >= a) one(b--);
  if (a > b) return;
  const double invM = 1.0 / double(m);
  const int k = a - uFirst;
  equalAreaRow(squareCoordinate(v, invM), invM, radius_, a, b - a + 1, hRow + a, out.x + k,
               out.y + k, out.z + k);
}

void OctahedralChart::scatteredPositions(const std::int32_t* u, const std::int32_t* v,
                                         const float* h, std::size_t n, RowOut out) const {
  if (mapping_ != Mapping::kEqualArea) {
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d p = position(u[k], v[k], double(h[k]));
      out.x[k] = p.x(), out.y[k] = p.y(), out.z[k] = p.z();
    }
    return;
  }
  const int m = grid().m();
  equalAreaScattered(m, 1.0 / double(m), radius_, u, v, h, n, out.x, out.y, out.z);
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
