#pragma once
#include <vector>

#include "core/chart.hpp"

namespace ps::core {

// Paper 003's chart (equations 1-5):
//   latitude  = v*pi/m - pi/2,   longitude = 2*u*pi/m - pi,
//   position  = (r + h) * (cos lon cos lat, sin lon cos lat, sin lat).
// u = 0 and u = m are the same meridian; rows v = 0 (south pole) and v = m (north pole) each
// collapse to one point. Per-row and per-column sines and cosines are tabulated so that a grid
// vertex's position costs a handful of multiplies.
class LatLongChart final : public Chart {
 public:
  // Throws InputError for a non-positive or non-finite radius.
  LatLongChart(GridSize grid, double radius);

  std::string name() const override { return "latlong"; }
  Eigen::Vector3d position(int u, int v, double h) const override {
    return (radius_ + h) * direction(u, v);
  }
  void rowPositions(int v, int uFirst, int uLast, const float* hRow, RowOut out) const override {
    const double cl = cosLat_[std::size_t(v)], sl = sinLat_[std::size_t(v)], r0 = radius_;
    const double* cosLon = cosLon_.data() + uFirst;
    const double* sinLon = sinLon_.data() + uFirst;
    const float* h = hRow + uFirst;
    double* __restrict x = out.x;
    double* __restrict y = out.y;
    double* __restrict z = out.z;
    const int n = uLast - uFirst + 1;
    for (int k = 0; k < n; ++k) {  // position()'s arithmetic, in its order
      const double r = r0 + double(h[k]);
      x[k] = r * (cosLon[k] * cl);
      y[k] = r * (sinLon[k] * cl);
      z[k] = r * sl;
    }
  }
  void scatteredPositions(const std::int32_t* u, const std::int32_t* v, const float* h,
                          std::size_t n, RowOut out) const override;
  Eigen::Vector3d up(int u, int v) const override { return direction(u, v); }
  Eigen::Vector3d positionAt(double u, double v, double h) const override;
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override;
  bool wrapsU() const override { return true; }
  bool hasPoleRows() const override { return true; }
  double sphereRadius() const override { return radius_; }

  // Unit direction of grid vertex (u, v); exact at the poles and on the seam.
  Eigen::Vector3d direction(int u, int v) const {
    const double cl = cosLat_[std::size_t(v)];
    return {cosLon_[std::size_t(u)] * cl, sinLon_[std::size_t(u)] * cl, sinLat_[std::size_t(v)]};
  }
  double latitude(double v) const;
  double longitude(double u) const;

 private:
  double radius_;
  std::vector<double> cosLon_, sinLon_, cosLat_, sinLat_;
};

}  // namespace ps::core
