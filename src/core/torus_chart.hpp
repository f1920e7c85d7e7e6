#pragma once
#include <vector>

#include "core/chart.hpp"

namespace ps::core {

// A torus (issue 28; paper 003's conclusion: "other topologies, such as the torus"): u goes
// round the big circle, v round the tube, both through 2 pi over the grid:
//   alpha = 2 pi u / m,   beta = 2 pi v / m,   r = minorRadius + h,
//   position = ((R + r cos beta) cos alpha, (R + r cos beta) sin alpha, r sin beta),
// heights displacing along the tube's outward normal (cos beta cos alpha, cos beta sin alpha,
// sin beta). v = 0 is the outer equator, v = m/2 the inner one. Columns 0 and m are glued by
// translation (a seam, as lat-long's), rows 0 and m likewise; the four corners are one point.
// m^2 distinct points, Euler characteristic 0.
//
// sphereRadius() is 0: the surface is no sphere about the origin, and the layers that read
// sphereRadius() > 0 as one (the tessellator's horizon occluder, great-circle strokes) must not
// treat the hole's ball as solid. The lengths are majorRadius() and minorRadius(); heights are
// limited to a quarter of the minor radius.
//
// Per-column and per-row sines and cosines are tabulated, symmetric bit for bit (entry m is
// entry 0, entry m - k mirrors entry k), so twins are one point bit for bit and the grid's
// mirror v -> m - v is the torus's z -> -z exactly (core::Chart::gluedImages relies on it).
class TorusChart final : public Chart {
 public:
  // Throws InputError unless 0 < minorRadius < majorRadius, both finite.
  TorusChart(GridSize grid, double majorRadius, double minorRadius);

  std::string name() const override { return "torus"; }
  Eigen::Vector3d position(int u, int v, double h) const override {
    const std::size_t i = std::size_t(u), j = std::size_t(v);
    const double r = minor_ + h, rho = major_ + r * cosV_[j];
    return {rho * cosU_[i], rho * sinU_[i], r * sinV_[j]};
  }
  void rowPositions(int v, int uFirst, int uLast, const float* hRow, RowOut out) const override {
    const double cv = cosV_[std::size_t(v)], sv = sinV_[std::size_t(v)];
    const double* cosU = cosU_.data() + uFirst;
    const double* sinU = sinU_.data() + uFirst;
    const float* h = hRow + uFirst;
    double* __restrict x = out.x;
    double* __restrict y = out.y;
    double* __restrict z = out.z;
    const int n = uLast - uFirst + 1;
    for (int k = 0; k < n; ++k) {  // position()'s arithmetic, in its order
      const double r = minor_ + double(h[k]), rho = major_ + r * cv;
      x[k] = rho * cosU[k];
      y[k] = rho * sinU[k];
      z[k] = r * sv;
    }
  }
  void scatteredPositions(const std::int32_t* u, const std::int32_t* v, const float* h,
                          std::size_t n, RowOut out) const override {
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d p = position(u[k], v[k], double(h[k]));
      out.x[k] = p.x(), out.y[k] = p.y(), out.z[k] = p.z();
    }
  }
  Eigen::Vector3d up(int u, int v) const override {
    const std::size_t i = std::size_t(u), j = std::size_t(v);
    return {cosV_[j] * cosU_[i], cosV_[j] * sinU_[i], sinV_[j]};
  }
  Eigen::Vector3d positionAt(double u, double v, double h) const override;
  // The nearest point's grid coordinates: round the big circle by p's azimuth, round the tube by
  // its angle about the tube's centre circle. nullopt on the torus's axis or its centre circle.
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override;
  bool wrapsU() const override { return true; }
  bool hasPoleRows() const override { return false; }
  Gluing gluing() const override { return {SideGluing::kSeam, SideGluing::kSeam}; }
  GridPoint canonical(int u, int v) const override {
    const int m = grid().m();
    return {u == m ? 0 : u, v == m ? 0 : v};
  }
  int twins(int u, int v, GridPoint out[4]) const override;
  double sphereRadius() const override { return 0.0; }
  double heightLimit() const override { return 0.25 * minor_; }

  double majorRadius() const { return major_; }
  double minorRadius() const { return minor_; }

 private:
  double major_, minor_;
  std::vector<double> cosU_, sinU_, cosV_, sinV_;
};

}  // namespace ps::core
