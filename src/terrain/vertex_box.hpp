#pragma once
#include <algorithm>
#include <string>
#include <vector>

#include "core/chart.hpp"
#include "core/grid.hpp"

namespace ps::terrain {

// A rectangle of grid vertices that may wrap across the u = 0 / u = m seam. u is kept
// "unwrapped": uBegin may be negative or uEnd beyond m, meaning the rectangle continues on the
// other side of the seam. Rows are clamped to [0, m]. Empty when vBegin > vEnd.
struct VertexBox {
  int uBegin = 0, uEnd = -1;  // inclusive, unwrapped
  int vBegin = 0, vEnd = -1;  // inclusive, within [0, m]

  static VertexBox none() { return {}; }
  static VertexBox all(const core::GridSize& g) { return {0, g.m(), 0, g.m()}; }
  static VertexBox point(core::GridPoint p) { return {p.u, p.u, p.v, p.v}; }

  bool empty() const { return vBegin > vEnd || uBegin > uEnd; }
  bool coversAllColumns(const core::GridSize& g) const { return uEnd - uBegin >= g.m(); }

  // Chebyshev dilation by d vertices; wraps in u on a seamed chart, clamps in v.
  VertexBox grown(int d, const core::GridSize& g, bool wrapsU) const {
    if (empty()) return *this;
    VertexBox r{uBegin - d, uEnd + d, std::max(0, vBegin - d), std::min(g.m(), vEnd + d)};
    normalise(r, g, wrapsU);
    return r;
  }

  VertexBox unite(const VertexBox& o, const core::GridSize& g, bool wrapsU) const {
    if (empty()) return o;
    if (o.empty()) return *this;
    VertexBox r;
    r.vBegin = std::min(vBegin, o.vBegin);
    r.vEnd = std::max(vEnd, o.vEnd);
    if (coversAllColumns(g) || o.coversAllColumns(g)) {
      r.uBegin = 0, r.uEnd = g.m();
      return r;
    }
    // Choose the shift of o (by a multiple of m) that gives the smallest union in u.
    const int m = g.m();
    int best = -1;
    for (int shift : {0, -m, m}) {
      if (shift != 0 && !wrapsU) continue;
      const int b = std::min(uBegin, o.uBegin + shift), e = std::max(uEnd, o.uEnd + shift);
      if (best < 0 || e - b < r.uEnd - r.uBegin) r.uBegin = b, r.uEnd = e, best = 1;
    }
    normalise(r, g, wrapsU);
    return r;
  }

  // Calls f(uFirst, uLast) for the one or two in-grid column ranges the region covers.
  template <class F>
  void forEachColumnRange(const core::GridSize& g, F&& f) const {
    if (empty()) return;
    const int m = g.m();
    if (coversAllColumns(g)) return f(0, m);
    if (uBegin < 0) {
      f(0, uEnd);
      f(uBegin + m, m);
    } else if (uEnd > m) {
      f(uBegin, m);
      f(0, uEnd - m);
    } else {
      f(uBegin, uEnd);
    }
  }

  std::string describe() const {
    return "u[" + std::to_string(uBegin) + "," + std::to_string(uEnd) + "] v[" +
           std::to_string(vBegin) + "," + std::to_string(vEnd) + "]";
  }

 private:
  static void normalise(VertexBox& r, const core::GridSize& g, bool wrapsU) {
    const int m = g.m();
    if (!wrapsU) {
      r.uBegin = std::max(0, r.uBegin), r.uEnd = std::min(m, r.uEnd);
      return;
    }
    if (r.uEnd - r.uBegin >= m) {
      r.uBegin = 0, r.uEnd = m;
      return;
    }
    while (r.uBegin < -m) r.uBegin += m, r.uEnd += m;
    while (r.uBegin > m) r.uBegin -= m, r.uEnd -= m;
  }
};

// Limits on u + v and u - v (inclusive) that cut the corners off a region's rectangle, which
// then holds an octagon. An edit's disc is no rectangle where the grid folds along its
// diagonals: on the octahedral chart a disc about a pole is a triangle in each of the grid's
// corners, or a diamond about its centre, half of its box, and the error bounds above the box's
// other half need no update (ErrorBounds::update; edit::EditPipeline sets them from the
// footprint). Only on charts without a u seam, whose regions' columns are in the grid.
struct Diagonals {
  static constexpr int kOpen = 1 << 28;   // no limit; far beyond any grid and its growth
  int sumMin = -kOpen, sumMax = kOpen;    // u + v
  int diffMin = -kOpen, diffMax = kOpen;  // u - v

  // Limits that hold no vertex, for add() to widen.
  static Diagonals nothing() { return {kOpen, -kOpen, kOpen, -kOpen}; }
  bool holdsNothing() const { return sumMin > sumMax || diffMin > diffMax; }
  void add(int u, int v) {
    sumMin = std::min(sumMin, u + v), sumMax = std::max(sumMax, u + v);
    diffMin = std::min(diffMin, u - v), diffMax = std::max(diffMax, u - v);
  }
  // Chebyshev dilation by d: the diagonals move by 2d.
  Diagonals grown(int d) const {
    return {sumMin - 2 * d, sumMax + 2 * d, diffMin - 2 * d, diffMax + 2 * d};
  }
  Diagonals hull(const Diagonals& o) const {
    return {std::min(sumMin, o.sumMin), std::max(sumMax, o.sumMax), std::min(diffMin, o.diffMin),
            std::max(diffMax, o.diffMax)};
  }
  // The limits of the region's image under u -> m - u and/or v -> m - v (core::Chart::Flips).
  Diagonals flipped(int m, bool flipU, bool flipV) const {
    Diagonals d = *this;
    if (flipU) d = {m - d.diffMax, m - d.diffMin, m - d.sumMax, m - d.sumMin};
    if (flipV) d = {m + d.diffMin, m + d.diffMax, d.sumMin - m, d.sumMax - m};
    return d;
  }
  // The columns of row v within the limits: [firstColumn, lastColumn], none when first > last.
  int firstColumn(int v) const { return std::max(sumMin - v, diffMin + v); }
  int lastColumn(int v) const { return std::min(sumMax - v, diffMax + v); }
};

// A rectangle with its corners cut by diagonals (open: the rectangle).
struct CutBox {
  VertexBox box;
  Diagonals cut;
};

// The region and its images across the chart's glued sides (core::Chart::gluedImages: mirrored
// sides, a seam between the rows v = 0 and v = m): on the octahedral chart and the torus an
// edit's dirty box stands for its images too, and the error bounds compute a level's regions'
// images where they reach such a side (`acrossMidlines` false). On other charts: the region.
inline std::vector<VertexBox> gluedImages(const core::Chart& chart, const VertexBox& r,
                                          bool acrossMidlines = true) {
  if (r.empty()) return {};
  if (!chart.gluesSidesBeyondSeam()) return {r};
  core::GridBox boxes[4];
  const int n = chart.gluedImages({r.uBegin, r.uEnd, r.vBegin, r.vEnd}, acrossMidlines, boxes);
  std::vector<VertexBox> out;
  out.reserve(std::size_t(n));
  for (int k = 0; k < n; ++k)
    out.push_back({boxes[k].uBegin, boxes[k].uEnd, boxes[k].vBegin, boxes[k].vEnd});
  return out;
}

// The same for a cut region: each image's diagonals flipped as its rectangle is.
inline std::vector<CutBox> gluedImages(const core::Chart& chart, const CutBox& r,
                                       bool acrossMidlines = true) {
  if (r.box.empty()) return {};
  if (!chart.gluesSidesBeyondSeam()) return {r};
  core::GridBox boxes[4];
  core::Chart::Flips flips[4];
  const int n = chart.gluedImages({r.box.uBegin, r.box.uEnd, r.box.vBegin, r.box.vEnd},
                                  acrossMidlines, boxes, flips);
  std::vector<CutBox> out;
  out.reserve(std::size_t(n));
  for (int k = 0; k < n; ++k)
    out.push_back({{boxes[k].uBegin, boxes[k].uEnd, boxes[k].vBegin, boxes[k].vEnd},
                   r.cut.flipped(chart.grid().m(), flips[k].u, flips[k].v)});
  return out;
}

}  // namespace ps::terrain
