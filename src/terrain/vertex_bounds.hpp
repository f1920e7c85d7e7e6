#pragma once
// The bound codes of single vertices of one level, the scalar path of ErrorBounds (error_bounds.cpp
// includes this; nothing else should): the general diamond, for the vertices on the grid's edges
// and the seam and for the levels above the row kernels (bound_kernels.hpp), and level 0's
// leaves. The row kernels repeat these formulas in the same order, so both paths give the same
// codes bit for bit.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/grid.hpp"
#include "terrain/bound_code.hpp"
#include "terrain/bound_kernels.hpp"
#include "terrain/diamond.hpp"
#include "terrain/error_bounds.hpp"
#include "terrain/exact_deviation.hpp"

namespace ps::terrain::detail {

template <class ChartT>
class VertexBounds {
 public:
  // boxes: positions computed ahead (null: none).
  VertexBounds(const ChartT& chart, const float* heights, BoundCodes* codes, int level,
               ErrorRule rule, bool withRadii, const PositionBoxes* boxes = nullptr)
      : sampler_{chart, heights, chart.grid(), boxes},
        g_(chart.grid()),
        codes_(codes),
        level_(level),
        s_(levelHalfSize(level)),
        rule_(rule),
        withRadii_(withRadii) {}

  // Stores p's codes (a leaf's at level 0); returns the largest error code among p's children
  // in the grid, which the lattice keeps beside p's own (0 for a leaf).
  std::uint16_t compute(GridPoint p) const {
    if (level_ == 0) {
      leaf(p);
      return 0;
    }
    return vertex(p);
  }

  // The general diamond. Returns the largest error code among p's children in the grid.
  std::uint16_t vertex(GridPoint p) const {
    const Diamond d = Diamond::of(p);
    const Eigen::Vector3d P = sampler_.pos(p);
    const Children c = children(d, P);
    const double childEps = BoundCode::decode(c.code);
    const double e = error(d, P, childEps);
    // A bound the children already give keeps their code: encodeUp(decode(c)) == c, so this
    // is the same code without the encoding's lookups.
    const std::uint16_t errorCode = e == childEps ? c.code : BoundCode::encodeUp(e);
    codes_[g_.index(p.u, p.v)] = {errorCode,
                                  withRadii_ ? BoundCode::encodeUp(c.radius) : std::uint16_t(0)};
    return c.code;
  }

  // Level 0 is half of all vertices: edge vertices of half-size 1, no children, no grid vertex
  // inside their triangles but their corners. The same values as vertex(), without the general
  // diamond (7.8 -> 4.4 ms of a 513² build).
  void leaf(GridPoint p) const {
    const bool horizontal = (p.u & 1) != 0;
    const GridPoint b0 = horizontal ? GridPoint{p.u - 1, p.v} : GridPoint{p.u, p.v - 1};
    const GridPoint b1 = horizontal ? GridPoint{p.u + 1, p.v} : GridPoint{p.u, p.v + 1};
    const Eigen::Vector3d P = sampler_.pos(p);
    const Eigen::Vector3d B0 = sampler_.pos(b0), B1 = sampler_.pos(b1);
    double radius = 0.0;
    if (withRadii_) {
      // sqrt is monotone and correctly rounded: one sqrt of the largest square is the largest
      // of the four distances, bit for bit.
      double r2 = std::max((B0 - P).squaredNorm(), (B1 - P).squaredNorm());
      const GridPoint a0 = horizontal ? GridPoint{p.u, p.v - 1} : GridPoint{p.u - 1, p.v};
      const GridPoint a1 = horizontal ? GridPoint{p.u, p.v + 1} : GridPoint{p.u + 1, p.v};
      if (inGrid(g_, a0)) r2 = std::max(r2, (sampler_.pos(a0) - P).squaredNorm());
      if (inGrid(g_, a1)) r2 = std::max(r2, (sampler_.pos(a1) - P).squaredNorm());
      radius = std::sqrt(r2);
    }
    const Eigen::Vector3d mid = 0.5 * (B0 + B1);
    const double e = (P - mid).norm();
    codes_[g_.index(p.u, p.v)] = {BoundCode::encodeUp(e),
                                  withRadii_ ? BoundCode::encodeUp(radius) : std::uint16_t(0)};
  }

 private:
  struct Children {
    std::uint16_t code = 0;  // the largest child error code
    double radius = 0.0;     // a ball around P holding every child's ball (and the corners)
  };

  // Codes are monotone: the largest child code is the largest child bound, one table lookup
  // instead of four (the 256 KB table does not fit the L1 cache).
  Children children(const Diamond& d, const Eigen::Vector3d& P) const {
    Children out;
    int childrenInGrid = 0;
    for (int i = 0; i < d.childCount; ++i) {
      const GridPoint c = d.children[std::size_t(i)];
      if (!inGrid(g_, c)) continue;
      ++childrenInGrid;
      const std::size_t ci = g_.index(c.u, c.v);
      out.code = std::max(out.code, codes_[ci].error);
      if (withRadii_) {
        out.radius = std::max(out.radius, (double(BoundCode::decode(codes_[ci].radius)) +
                                           (sampler_.pos(c) - P).norm()) *
                                              kRadiusMargin);
      }
    }
    // Every corner of the diamond is a corner of one of the four children's diamonds, which
    // their radii cover: |P(corner) - P| <= radius(child) + |P(child) - P|, and the margin puts
    // that term far above the rounding of the direct distance. So the corners only matter where
    // a child falls outside the grid.
    if (withRadii_ && childrenInGrid < 4) {
      double corner2 = 0.0;
      for (GridPoint c : {d.base0, d.base1, d.apex0, d.apex1}) {
        if (inGrid(g_, c)) corner2 = std::max(corner2, (sampler_.pos(c) - P).squaredNorm());
      }
      out.radius = std::max(out.radius, std::sqrt(corner2));
    }
    return out;
  }

  // The diamond's error bound by the rule, given its children's.
  double error(const Diamond& d, const Eigen::Vector3d& P, double childEps) const {
    // At level 0 a diamond's triangles hold no grid vertex but their corners and v itself, so
    // the exact deviation is the midpoint error: the wedgie formula below (half of all vertices
    // take this path, so skipping the triangle scans matters).
    if (rule_ == ErrorRule::kHybridExact && level_ == 1) {
      // A level-1 diamond's triangles hold their corners (deviation 0), v on the hypotenuse
      // (the midpoint error) and the midpoints of their legs, which are v's four children:
      // their own midpoint errors, already bounded by childEps. So the exact maximum is this,
      // without scanning (a quarter of all vertices).
      const Eigen::Vector3d mid = 0.5 * (sampler_.pos(d.base0) + sampler_.pos(d.base1));
      return std::max(childEps, (P - mid).norm());
    }
    if (rule_ == ErrorRule::kHybridExact && s_ <= ErrorBounds::kExactMaxHalfSize && level_ > 0) {
      // The triangles' grid points: corners (deviation 0), legs (the children's hypotenuses,
      // covered by childEps), the shared hypotenuse and the two interiors.
      double e = std::max(childEps, hypotenuseDeviation(sampler_, d.base0, d.base1));
      if (inGrid(g_, d.apex0))
        e = std::max(e, interiorDeviation(sampler_, d.apex0, d.base0, d.base1));
      if (inGrid(g_, d.apex1))
        e = std::max(e, interiorDeviation(sampler_, d.apex1, d.base1, d.base0));
      return e;
    }
    const Eigen::Vector3d mid = 0.5 * (sampler_.pos(d.base0) + sampler_.pos(d.base1));
    return childEps + (P - mid).norm();
  }

  const Sampler<ChartT> sampler_;
  const core::GridSize g_;
  BoundCodes* const codes_;
  const int level_;
  const int s_;
  const ErrorRule rule_;
  const bool withRadii_;
};

}  // namespace ps::terrain::detail
