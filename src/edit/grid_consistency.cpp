#include "edit/grid_consistency.hpp"

#include <algorithm>

namespace ps::edit {

void applyToVertex(const core::Chart& chart, std::span<float> heights, int u, int v, float h) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  if (chart.hasPoleRows() && (v == 0 || v == m)) {
    std::fill_n(heights.begin() + std::ptrdiff_t(g.index(0, v)), g.side(), h);
    return;
  }
  heights[g.index(u, v)] = h;
  if (chart.wrapsU() && (u == 0 || u == m)) heights[g.index(m - u, v)] = h;
}

void enforceConsistency(const core::Chart& chart, std::span<float> heights,
                        const terrain::GridRegion& region) {
  if (region.empty()) return;
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const int v0 = std::max(0, region.vBegin), v1 = std::min(m, region.vEnd);
  if (chart.wrapsU()) {
    bool seam = false;
    region.forEachColumnRange(g, [&](int a, int b) { seam |= (a == 0 || b == m); });
    if (seam) {
      for (int v = v0; v <= v1; ++v) heights[g.index(m, v)] = heights[g.index(0, v)];
    }
  }
  if (chart.hasPoleRows()) {
    for (int v : {0, m}) {
      if (v < v0 || v > v1) continue;
      const float h = heights[g.index(0, v)];
      std::fill_n(heights.begin() + std::ptrdiff_t(g.index(0, v)), g.side(), h);
    }
  }
}

}  // namespace ps::edit
