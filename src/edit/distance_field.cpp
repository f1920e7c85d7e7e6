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
  radius_ = chart_->radius();
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
  const core::GridPoint p = chart_->canonical(u, v);  // a pole row is one point
  return (chart_->position(p.u, p.v, 0.0) - pc_).squaredNorm();
}

}  // namespace ps::edit
