#pragma once
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/chart.hpp"
#include "core/grid.hpp"
#include "core/latlong_chart.hpp"

namespace ps::edit {

// The one distance predicate of the edit layer: the squared 3D (Euclidean, chord) distance in m^2
// between grid vertex (u, v) and a centre vertex, both taken on the reference sphere (height 0),
// i.e. |f(u, v) - f(uc, vc)|^2 with paper 003's f (equation 5). Heights are deliberately left out:
// the deformation area and the Gaussian then do not depend on what was sculpted before (a stroke
// cannot "steal" its own footprint), and V_d is always one connected set that region growing can
// find exactly (docs/EDITING.md).
//
// On the lat-long chart it is evaluated as
//     d^2 = R^2 * (E_v + F_v * S_k),   E_v = (z_v - z_c)^2 + (rho_v - rho_c)^2,   F_v = 2 rho_v
//     rho_c, S_k = 2 sin^2(pi k / m),   k = the seam-wrapped column distance |u - uc| folded into
//     [0, m/2],
// with z = sin(latitude), rho = cos(latitude) taken bit-for-bit from the chart's tables. This is
// the exact chord length (|a - b|^2 = (z - zc)^2 + rho^2 + rhoc^2 - 2 rho rhoc cos(dlon)), free of
// the cancellation of 2R^2(1 - cos), and - because F_v >= 0 and S_k is tabulated non-decreasing -
// it is monotone in k in floating point: within a row, the vertices with d^2 <= r^2 are exactly
// those with k <= K_v. Seam twins get the same k, every vertex of a pole row the same value
// (rho = 0 there), so twins and pole rows always agree.
//
// On any other chart it is (chart.position(u, v, 0) - chart.position(uc, vc, 0)).squaredNorm(),
// summed as dx^2 + dy^2 + dz^2; rowDistances2 computes whole runs of a row with the chart's row
// positions, bit for bit the same.
class DistanceField {
 public:
  // Tables are built once per chart (O(m)); setCentre() is O(1).
  explicit DistanceField(std::shared_ptr<const core::Chart> chart);

  const core::Chart& chart() const { return *chart_; }
  const core::GridSize& grid() const { return grid_; }
  // Non-null when the fast lat-long path is in use.
  const core::LatLongChart* latLong() const { return latLong_; }
  double sphereRadius() const { return radius_; }

  // Centre vertex; stored canonically (seam column u = m as u = 0, a pole as u = 0).
  void setCentre(core::GridPoint c);
  core::GridPoint centre() const { return centre_; }

  // The predicate's value for any in-grid vertex (identical arithmetic on every path that uses it).
  double distance2(int u, int v) const {
    if (latLong_) return distance2(row(v), fold(u));
    return genericDistance2(u, v);
  }

  // distance2(u, v) of row v's vertices u = uFirst .. uLast into out[u - uFirst], bit for bit:
  // region growing and the brush take a row's distances at once (on the octahedral chart by
  // its vectorised row positions instead of a position per vertex).
  void rowDistances2(int v, int uFirst, int uLast, double* out) const;

  // Lat-long fast path: per-row terms and the folded column distance.
  struct Row {
    double e = 0, f = 0;
  };
  Row row(int v) const {
    const double dz = z_[std::size_t(v)] - zc_, dr = rho_[std::size_t(v)] - rhoc_;
    return {dz * dz + dr * dr, 2.0 * rho_[std::size_t(v)] * rhoc_};
  }
  double distance2(const Row& r, int k) const { return r2_ * (r.e + r.f * s_[std::size_t(k)]); }
  // Column distance from the centre across the seam: 0 .. m/2 (u = 0 and u = m give the same).
  int fold(int u) const {
    int d = u - centre_.u;
    if (d < 0) d += m_;
    return d <= m_ - d ? d : m_ - d;
  }
  int halfM() const { return m_ / 2; }

 private:
  double genericDistance2(int u, int v) const;

  std::shared_ptr<const core::Chart> chart_;
  const core::LatLongChart* latLong_ = nullptr;
  core::GridSize grid_;
  int m_ = 0;
  double radius_ = 0, r2_ = 0;
  std::vector<double> z_, rho_, s_;  // per row; per folded column distance
  std::vector<float> zeroHeights_;   // generic path: a row of heights 0 for rowPositions
  core::GridPoint centre_;
  double zc_ = 0, rhoc_ = 0;
  Eigen::Vector3d pc_ = Eigen::Vector3d::Zero();  // generic path
};

}  // namespace ps::edit
