#pragma once
// The exact deviations of ErrorBounds' hybrid rule (error_bounds.cpp and vertex_bounds.hpp
// include this; nothing else should): the largest 3D distance between the surface at the grid
// points of a diamond's triangles and the triangles' own linear interpolant.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <type_traits>

#include "core/flat_chart.hpp"
#include "core/grid.hpp"
#include "terrain/diamond.hpp"
#include "terrain/position_boxes.hpp"

namespace ps::terrain::detail {

// A chart's surface point of grid point p, from the heights (or from positions computed ahead,
// the same bits).
template <class ChartT>
struct Sampler {
  const ChartT& chart;
  const float* h;
  core::GridSize g;
  const PositionBoxes* boxes = nullptr;
  Eigen::Vector3d pos(GridPoint p) const {
    if (boxes) {
      const PositionBoxes::Row r = boxes->row(p.v, p.u, p.u);
      if (r.x) return {*r.x, *r.y, *r.z};
    }
    return chart.position(p.u, p.v, double(h[g.index(p.u, p.v)]));
  }
};

// Largest |P(q) - L_T(q)| over the grid points q strictly inside triangle (a, b0, b1) (right
// angle at a), visited row span by row span, L_T from q's barycentric weights. The points on
// its edges are left to the callers: the legs are the hypotenuses of v's children, on which L_T
// is the children's own interpolant, so the children's exact bounds already cover them; the
// hypotenuse is shared with the diamond's other triangle (hypotenuseDeviation, once for both).
template <class ChartT>
double interiorDeviation(const Sampler<ChartT>& s, GridPoint a, GridPoint b0, GridPoint b1) {
  if constexpr (std::is_same_v<ChartT, core::FlatChart>) {
    // x and y are linear in (u, v) on a flat chart, so the deviation is the height's alone:
    // the same value without the rounding noise of the two planar components.
    const double ha = s.h[s.g.index(a.u, a.v)];
    const double d0 = s.h[s.g.index(b0.u, b0.v)] - ha, d1 = s.h[s.g.index(b1.u, b1.v)] - ha;
    double worst = 0.0;
    forEachGridPointInTriangle(
        a, b0, b1,
        [&](int u, int v, double w0, double w1) {
          worst =
              std::max(worst, std::abs(double(s.h[s.g.index(u, v)]) - (ha + w0 * d0 + w1 * d1)));
        },
        TriangleSet::kOpen);
    return worst;
  } else {
    const Eigen::Vector3d pa = s.pos(a), d0 = s.pos(b0) - pa, d1 = s.pos(b1) - pa;
    double worst2 = 0.0;
    forEachGridPointInTriangle(
        a, b0, b1,
        [&](int u, int v, double w0, double w1) {
          worst2 = std::max(worst2, (s.pos({u, v}) - (pa + w0 * d0 + w1 * d1)).squaredNorm());
        },
        TriangleSet::kOpen);
    return std::sqrt(worst2);
  }
}

// Largest deviation of the grid points strictly between b0 and b1 (v among them) from the
// segment b0-b1, which is where both of the diamond's triangles put them.
template <class ChartT>
double hypotenuseDeviation(const Sampler<ChartT>& s, GridPoint b0, GridPoint b1) {
  const int steps = std::max(std::abs(b1.u - b0.u), std::abs(b1.v - b0.v));
  const int du = (b1.u - b0.u) / steps, dv = (b1.v - b0.v) / steps;
  const double inv = 1.0 / steps;
  if constexpr (std::is_same_v<ChartT, core::FlatChart>) {
    const double h0 = s.h[s.g.index(b0.u, b0.v)], dh = s.h[s.g.index(b1.u, b1.v)] - h0;
    double worst = 0.0;
    for (int k = 1; k < steps; ++k) {
      const double hq = s.h[s.g.index(b0.u + k * du, b0.v + k * dv)];
      worst = std::max(worst, std::abs(hq - (h0 + double(k) * inv * dh)));
    }
    return worst;
  } else {
    const Eigen::Vector3d p0 = s.pos(b0), d = s.pos(b1) - p0;
    double worst2 = 0.0;
    for (int k = 1; k < steps; ++k) {
      const Eigen::Vector3d q = s.pos({b0.u + k * du, b0.v + k * dv});
      worst2 = std::max(worst2, (q - (p0 + double(k) * inv * d)).squaredNorm());
    }
    return std::sqrt(worst2);
  }
}

}  // namespace ps::terrain::detail
