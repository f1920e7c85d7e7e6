#pragma once
// One Euro filters (Casiez, Roussel and Vogel, CHI 2012): a low-pass filter whose cutoff rises
// with speed, so a marker held still stops jittering while a moving one lags little.
//   cutoff = minCutoff + beta * |filtered speed|,  alpha = 1 / (1 + 1 / (2 pi cutoff dt)).
// For rotations the same rule runs on the angle between the last output and the new sample
// (a slerp by alpha), so the filter never leaves the rotation group.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ps::tracking {

struct OneEuroParams {
  double minCutoff = 1.0;  // Hz: the cutoff at rest (lower: less jitter, more lag at rest)
  double beta = 0.5;       // cutoff gain per unit of speed (units/s; higher: less lag moving)
  double dCutoff = 1.0;    // Hz: cutoff of the speed estimate
  bool operator==(const OneEuroParams&) const = default;
};

double oneEuroAlpha(double cutoffHz, double dt);

// Vector quantities (positions, metres).
class OneEuroVector {
 public:
  explicit OneEuroVector(OneEuroParams p = {}) : p_(p) {}
  Eigen::Vector3d filter(const Eigen::Vector3d& x, double dt);
  void reset() { initialised_ = false; }
  bool initialised() const { return initialised_; }
  const Eigen::Vector3d& value() const { return x_; }

 private:
  OneEuroParams p_;
  bool initialised_ = false;
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero(), dx_ = Eigen::Vector3d::Zero();
};

// Rotations (speed in radians per second).
class OneEuroRotation {
 public:
  explicit OneEuroRotation(OneEuroParams p = {}) : p_(p) {}
  Eigen::Quaterniond filter(const Eigen::Quaterniond& q, double dt);
  void reset() { initialised_ = false; }

 private:
  OneEuroParams p_;
  bool initialised_ = false;
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  double speed_ = 0;
};

}  // namespace ps::tracking
