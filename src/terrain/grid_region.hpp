#pragma once
#include <algorithm>
#include <string>
#include <vector>

#include "core/grid.hpp"

namespace ps::terrain {

// A rectangle of grid vertices that may wrap across the u = 0 / u = m seam. u is kept
// "unwrapped": uBegin may be negative or uEnd beyond m, meaning the rectangle continues on the
// other side of the seam. Rows are clamped to [0, m]. Empty when vBegin > vEnd.
struct GridRegion {
  int uBegin = 0, uEnd = -1;  // inclusive, unwrapped
  int vBegin = 0, vEnd = -1;  // inclusive, within [0, m]

  static GridRegion none() { return {}; }
  static GridRegion all(const core::GridSize& g) { return {0, g.m(), 0, g.m()}; }
  static GridRegion point(core::GridPoint p) { return {p.u, p.u, p.v, p.v}; }

  bool empty() const { return vBegin > vEnd || uBegin > uEnd; }
  bool coversAllColumns(const core::GridSize& g) const { return uEnd - uBegin >= g.m(); }

  // Chebyshev dilation by d vertices; wraps in u on a seamed chart, clamps in v.
  GridRegion grown(int d, const core::GridSize& g, bool wrapsU) const {
    if (empty()) return *this;
    GridRegion r{uBegin - d, uEnd + d, std::max(0, vBegin - d), std::min(g.m(), vEnd + d)};
    normalise(r, g, wrapsU);
    return r;
  }

  GridRegion unite(const GridRegion& o, const core::GridSize& g, bool wrapsU) const {
    if (empty()) return o;
    if (o.empty()) return *this;
    GridRegion r;
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
  static void normalise(GridRegion& r, const core::GridSize& g, bool wrapsU) {
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

// On a chart that folds its sides (core/octahedral_chart.hpp, where (u, 0) is (m - u, 0) and
// (0, v) is (0, m - v)), the grid is symmetric under u -> m - u and v -> m - v (the sphere's
// mirrors x -> -x and y -> -y), and a disc about a centre in one quadrant of the grid, met in
// another quadrant across a fold or a midline, lies there inside a mirror image of its own
// quadrant's part (a point and its mirror are nearer the centre on the centre's side). The
// images that can hold such a part: the box itself, its image under u -> m - u where it
// reaches a side v = 0 or m or the midline u = m/2, under v -> m - v where it reaches a side
// u = 0 or m or the midline v = m/2, and under both where both hold. For a box that spans
// quadrants the images only add work. `acrossMidlines` false: the images across the sides only
// (a side vertex's twin; what the error bounds need level by level).
inline std::vector<GridRegion> foldImages(const GridRegion& r, const core::GridSize& g,
                                          bool acrossMidlines = true) {
  if (r.empty()) return {};
  const int m = g.m();
  const bool flipU =
      r.vBegin <= 0 || r.vEnd >= m || (acrossMidlines && r.uBegin <= m / 2 && r.uEnd >= m / 2);
  const bool flipV =
      r.uBegin <= 0 || r.uEnd >= m || (acrossMidlines && r.vBegin <= m / 2 && r.vEnd >= m / 2);
  std::vector<GridRegion> out{r};
  if (flipU) out.push_back({m - r.uEnd, m - r.uBegin, r.vBegin, r.vEnd});
  if (flipV) out.push_back({r.uBegin, r.uEnd, m - r.vEnd, m - r.vBegin});
  if (flipU && flipV) out.push_back({m - r.uEnd, m - r.uBegin, m - r.vEnd, m - r.vBegin});
  return out;
}

}  // namespace ps::terrain
