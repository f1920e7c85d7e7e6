#include "edit/distance_field.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::edit {

DistanceField::DistanceField(std::shared_ptr<const core::Chart> chart)
    : chart_(std::move(chart)),
      grid_(chart_ ? chart_->grid() : core::GridSize(core::GridSize::kMinLevel)) {
  if (!chart_) throw core::InputError("distance field needs a chart");
  latLong_ = dynamic_cast<const core::LatLongChart*>(chart_.get());
  m_ = grid_.m();
  radius_ = chart_->sphereRadius();
  r2_ = radius_ * radius_;
  if (latLong_) {
    z_.resize(std::size_t(m_) + 1);
    rho_.resize(std::size_t(m_) + 1);
    for (int v = 0; v <= m_; ++v) {
      // The chart's own tables: cos(lon) is exactly 1 at u = m/2, so x there is cos(lat) bit for
      // bit.
      const Eigen::Vector3d d = latLong_->direction(m_ / 2, v);
      rho_[std::size_t(v)] = std::max(0.0, d.x());
      z_[std::size_t(v)] = d.z();
    }
    s_.resize(std::size_t(m_ / 2) + 1);
    for (int k = 0; k <= m_ / 2; ++k) {
      const double t = std::sin(std::numbers::pi * double(k) / double(m_));
      s_[std::size_t(k)] = 2.0 * t * t;
    }
    s_[0] = 0.0;
    s_[std::size_t(m_ / 2)] = 2.0;
    // Non-decreasing by construction (the predicate's monotonicity rests on it).
    for (std::size_t k = 1; k < s_.size(); ++k) s_[k] = std::max(s_[k], s_[k - 1]);
  } else {
    zeroHeights_.assign(std::size_t(m_) + 1, 0.0f);
  }
  setCentre({0, m_ / 2});
}

void DistanceField::setCentre(core::GridPoint c) {
  if (c.u < 0 || c.u > m_ || c.v < 0 || c.v > m_) {
    throw core::InputError("centre vertex (u=" + std::to_string(c.u) + ", v=" +
                           std::to_string(c.v) + ") lies outside the " + grid_.label() + " grid");
  }
  c = chart_->canonical(c.u, c.v);
  centre_ = c;
  if (latLong_) {
    zc_ = z_[std::size_t(c.v)];
    rhoc_ = rho_[std::size_t(c.v)];
  } else {
    pc_ = chart_->position(c.u, c.v, 0.0);
  }
}

double DistanceField::genericDistance2(int u, int v) const {
  const core::GridPoint c = chart_->canonical(u, v);  // a pole row is one point
  const Eigen::Vector3d p = chart_->position(c.u, c.v, 0.0);
  const double dx = p.x() - pc_.x(), dy = p.y() - pc_.y(), dz = p.z() - pc_.z();
  return dx * dx + dy * dy + dz * dz;
}

void DistanceField::rowDistances2(int v, int uFirst, int uLast, double* out) const {
  if (latLong_) {
    const Row r = row(v);
    for (int u = uFirst; u <= uLast; ++u) out[u - uFirst] = distance2(r, fold(u));
    return;
  }
  // The grid's first and last rows and columns go vertex by vertex: a vertex there may stand
  // for another (a pole, a seam, a fold) and is taken at its canonical vertex. Inside, every
  // vertex is its own, and rowPositions gives position()'s bits (height 0: r0 + 0.0f is r0).
  if (v == 0 || v == m_) {
    for (int u = uFirst; u <= uLast; ++u) out[u - uFirst] = genericDistance2(u, v);
    return;
  }
  int a = uFirst, b = uLast;
  if (a == 0 && a <= b) out[0] = genericDistance2(0, v), ++a;
  if (b == m_ && a <= b) out[b - uFirst] = genericDistance2(m_, v), --b;
  if (a > b) return;
  thread_local std::vector<double> x, y, z;
  const std::size_t n = std::size_t(b - a + 1);
  if (x.size() < n) x.resize(n), y.resize(n), z.resize(n);
  chart_->rowPositions(v, a, b, zeroHeights_.data(), {x.data(), y.data(), z.data()});
  const double cx = pc_.x(), cy = pc_.y(), cz = pc_.z();
  double* o = out + (a - uFirst);
  for (std::size_t k = 0; k < n; ++k) {
    const double dx = x[k] - cx, dy = y[k] - cy, dz = z[k] - cz;
    o[k] = dx * dx + dy * dy + dz * dz;
  }
}

}  // namespace ps::edit
