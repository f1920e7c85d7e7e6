#include "tracking/filter.hpp"

#include <cmath>
#include <numbers>

namespace ps::tracking {

double oneEuroAlpha(double cutoffHz, double dt) {
  if (!(dt > 0)) return 1.0;
  const double tau = 1.0 / (2.0 * std::numbers::pi * cutoffHz);
  return 1.0 / (1.0 + tau / dt);
}

Eigen::Vector3d OneEuroVector::filter(const Eigen::Vector3d& x, double dt) {
  if (!initialised_ || !(dt > 0)) {
    initialised_ = true;
    x_ = x;
    dx_.setZero();
    return x_;
  }
  const Eigen::Vector3d dx = (x - x_) / dt;
  dx_ += oneEuroAlpha(p_.dCutoff, dt) * (dx - dx_);
  const double cutoff = p_.minCutoff + p_.beta * dx_.norm();
  x_ += oneEuroAlpha(cutoff, dt) * (x - x_);
  return x_;
}

Eigen::Quaterniond OneEuroRotation::filter(const Eigen::Quaterniond& qIn, double dt) {
  Eigen::Quaterniond q = qIn.normalized();
  if (!initialised_ || !(dt > 0)) {
    initialised_ = true;
    q_ = q;
    speed_ = 0;
    return q_;
  }
  if (q_.dot(q) < 0) q.coeffs() = -q.coeffs();  // the nearer of q and -q
  const double angle = q_.angularDistance(q);
  speed_ += oneEuroAlpha(p_.dCutoff, dt) * (angle / dt - speed_);
  const double cutoff = p_.minCutoff + p_.beta * speed_;
  q_ = q_.slerp(oneEuroAlpha(cutoff, dt), q).normalized();
  return q_;
}

}  // namespace ps::tracking
