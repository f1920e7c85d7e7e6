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
  core::GridPoint twins[4];
  const int n = chart.twins(u, v, twins);
  for (int k = 0; k < n; ++k) heights[g.index(twins[k].u, twins[k].v)] = h;
}

void enforceConsistency(const core::Chart& chart, std::span<float> heights,
                        const terrain::VertexBox& region) {
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
  if (chart.gluesSidesBeyondSeam()) {
    // Mirrored sides (core/octahedral_chart.hpp), a seam between v = 0 and v = m (the torus):
    // the region's border vertices give their height to their twins.
    auto copyToTwins = [&](int u, int v) {
      core::GridPoint twins[4];
      const int n = chart.twins(u, v, twins);
      const float h = heights[g.index(u, v)];
      for (int k = 1; k < n; ++k) heights[g.index(twins[k].u, twins[k].v)] = h;
    };
    const core::Gluing gl = chart.gluing();
    if (gl.vSides == core::SideGluing::kMirror || gl.vSides == core::SideGluing::kSeam) {
      region.forEachColumnRange(g, [&](int u0, int u1) {
        for (int v : {0, m})
          if (v >= v0 && v <= v1)
            for (int u = u0; u <= u1; ++u) copyToTwins(u, v);
      });
    }
    if (gl.uSides == core::SideGluing::kMirror) {
      const int u0 = std::max(0, region.uBegin), u1 = std::min(m, region.uEnd);
      for (int u : {0, m})
        if (u >= u0 && u <= u1)
          for (int v = v0; v <= v1; ++v) copyToTwins(u, v);
    }
  }
}

}  // namespace ps::edit
