#pragma once
#include <vector>

#include "core/chart.hpp"

namespace ps::core {

// An open tube (issue 28; paper 003's conclusion: "other topologies, such as ... the
// cylinder"): u goes round the axis (z), v along it, the tube centred on the origin:
//   alpha = 2 pi u / m,   position = ((R + h) cos alpha, (R + h) sin alpha, L (v / m - 1/2)),
// heights displacing along the outward normal (cos alpha, sin alpha, 0). Columns 0 and m are
// glued by translation (a seam, as lat-long's); the ends v = 0 and v = m are open borders (a
// welded mesh's only border edges). m (m + 1) distinct points, an annulus: Euler
// characteristic 0.
//
// sphereRadius() is 0, as the torus's (core/torus_chart.hpp): an open tube is no sphere about the
// origin, and its inside is seen through its ends, so no ball about the origin is a solid
// occluder. The lengths are tubeRadius() and length(); heights are limited to a quarter of the
// tube's radius.
class CylinderChart final : public Chart {
 public:
  // Throws InputError unless the radius and the length are finite and positive.
  CylinderChart(GridSize grid, double radius, double length);

  std::string name() const override { return "cylinder"; }
  Eigen::Vector3d position(int u, int v, double h) const override {
    const std::size_t i = std::size_t(u);
    const double r = radius_ + h;
    return {r * cosU_[i], r * sinU_[i], z_[std::size_t(v)]};
  }
  void rowPositions(int v, int uFirst, int uLast, const float* hRow, RowOut out) const override {
    const double zv = z_[std::size_t(v)];
    const double* cosU = cosU_.data() + uFirst;
    const double* sinU = sinU_.data() + uFirst;
    const float* h = hRow + uFirst;
    double* __restrict x = out.x;
    double* __restrict y = out.y;
    double* __restrict z = out.z;
    const int n = uLast - uFirst + 1;
    for (int k = 0; k < n; ++k) {
      const double r = radius_ + double(h[k]);
      x[k] = r * cosU[k];
      y[k] = r * sinU[k];
      z[k] = zv;
    }
  }
  void scatteredPositions(const std::int32_t* u, const std::int32_t* v, const float* h,
                          std::size_t n, RowOut out) const override {
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d p = position(u[k], v[k], double(h[k]));
      out.x[k] = p.x(), out.y[k] = p.y(), out.z[k] = p.z();
    }
  }
  Eigen::Vector3d up(int u, int) const override {
    return {cosU_[std::size_t(u)], sinU_[std::size_t(u)], 0.0};
  }
  Eigen::Vector3d positionAt(double u, double v, double h) const override;
  // Round the axis by p's azimuth, along it by p's z (clamped to the tube). nullopt on the axis.
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override;
  bool wrapsU() const override { return true; }
  bool hasPoleRows() const override { return false; }
  double sphereRadius() const override { return 0.0; }
  double heightLimit() const override { return 0.25 * radius_; }

  double tubeRadius() const { return radius_; }
  double length() const { return length_; }

 private:
  double radius_, length_;
  std::vector<double> cosU_, sinU_, z_;
};

}  // namespace ps::core
