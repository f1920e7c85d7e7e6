#include "core/latlong_chart.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::core {

namespace {
constexpr double kPi = std::numbers::pi;
}

LatLongChart::LatLongChart(GridSize grid, double radius) : Chart(grid), radius_(radius) {
  if (!std::isfinite(radius) || radius <= 0.0) {
    throw InputError("planet radius " + std::to_string(radius) + " m must be positive and finite");
  }
  const int m = grid.m();
  cosLon_.resize(std::size_t(m) + 1);
  sinLon_.resize(std::size_t(m) + 1);
  cosLat_.resize(std::size_t(m) + 1);
  sinLat_.resize(std::size_t(m) + 1);
  for (int i = 0; i <= m; ++i) {
    const double lon = longitude(i);
    const double lat = latitude(i);
    cosLon_[std::size_t(i)] = std::cos(lon);
    sinLon_[std::size_t(i)] = std::sin(lon);
    cosLat_[std::size_t(i)] = std::cos(lat);
    sinLat_[std::size_t(i)] = std::sin(lat);
  }
  // The seam's two columns must be bitwise identical, and a pole row a single point: fix the
  // last bits that cos/sin of -pi and pi (and of +-pi/2) would otherwise leave.
  cosLon_[std::size_t(m)] = cosLon_[0] = -1.0;
  sinLon_[std::size_t(m)] = sinLon_[0] = 0.0;
  cosLat_[0] = cosLat_[std::size_t(m)] = 0.0;
  sinLat_[0] = -1.0;
  sinLat_[std::size_t(m)] = 1.0;
  if (m % 2 == 0) {
    cosLon_[std::size_t(m / 2)] = 1.0;
    sinLon_[std::size_t(m / 2)] = 0.0;
    cosLat_[std::size_t(m / 2)] = 1.0;
    sinLat_[std::size_t(m / 2)] = 0.0;
  }
}

namespace {
// position()'s arithmetic, in its order, over arrays: the loads from the tables are scattered,
// the arithmetic vectorises.
__attribute__((target_clones("avx512f", "avx2", "default"))) void scatteredLatLong(
    const double* __restrict cosLon, const double* __restrict sinLon,
    const double* __restrict cosLat, const double* __restrict sinLat, double r0,
    const std::int32_t* __restrict u, const std::int32_t* __restrict v, const float* __restrict h,
    std::size_t n, double* __restrict x, double* __restrict y, double* __restrict z) {
  for (std::size_t k = 0; k < n; ++k) {
    const double r = r0 + double(h[k]);
    const double cl = cosLat[v[k]];
    x[k] = r * (cosLon[u[k]] * cl);
    y[k] = r * (sinLon[u[k]] * cl);
    z[k] = r * sinLat[v[k]];
  }
}
}  // namespace

void LatLongChart::scatteredPositions(const std::int32_t* u, const std::int32_t* v, const float* h,
                                      std::size_t n, RowOut out) const {
  scatteredLatLong(cosLon_.data(), sinLon_.data(), cosLat_.data(), sinLat_.data(), radius_, u, v, h,
                   n, out.x, out.y, out.z);
}

double LatLongChart::latitude(double v) const {
  return v * kPi / grid().m() - kPi / 2;
}
double LatLongChart::longitude(double u) const {
  return 2.0 * u * kPi / grid().m() - kPi;
}

Eigen::Vector3d LatLongChart::positionAt(double u, double v, double h) const {
  const double lat = latitude(v), lon = longitude(u);
  return (radius_ + h) * Eigen::Vector3d(std::cos(lon) * std::cos(lat),
                                         std::sin(lon) * std::cos(lat), std::sin(lat));
}

std::optional<Eigen::Vector2d> LatLongChart::inverse(const Eigen::Vector3d& p) const {
  const double r = p.norm();
  if (!std::isfinite(r) || r <= 0.0 || r < 1e-12 * radius_) return std::nullopt;
  const double lat = std::asin(std::clamp(p.z() / r, -1.0, 1.0));
  double lon = std::atan2(p.y(), p.x());  // (-pi, pi]
  const double m = grid().m();
  const double u = (lon + kPi) * m / (2.0 * kPi);
  const double v = (lat + kPi / 2) * m / kPi;
  return Eigen::Vector2d(std::clamp(u, 0.0, m), std::clamp(v, 0.0, m));
}

}  // namespace ps::core
