#pragma once
// Positions computed ahead for ErrorBounds::update (error_bounds.cpp, bound_kernels.hpp and
// exact_deviation.hpp include this; nothing else should).
#include <algorithm>
#include <cstddef>
#include <vector>

#include "terrain/vertex_box.hpp"

namespace ps::terrain::detail {

// Positions of boxes of the grid, computed once for an update of the bounds (ErrorBounds::update
// on the octahedral chart, whose positions cost a division, a square root and two polynomials
// each, not a look-up): the row kernels of every level read rows of them instead of computing
// their rows afresh, level after level (six levels, each reading its region's every row), and
// the scalar path (Sampler) reads single points of them. Positions are rowPositions', which
// are position()'s bit for bit, so the codes are the same whichever path computed them.
struct PositionBoxes {
  struct Box {
    VertexBox area;  // within the grid
    Diagonals cut;   // the area's positions within the cut were computed (open: all)
    const double *x, *y, *z;
  };
  std::vector<Box> boxes;
  // Row v's positions from column uLo on (column u at [u - uLo]), when a box holds columns
  // uLo .. uHi of it; x is null otherwise.
  struct Row {
    const double *x = nullptr, *y = nullptr, *z = nullptr;
  };
  Row row(int v, int uLo, int uHi) const {
    for (const Box& b : boxes) {
      const VertexBox& a = b.area;
      if (v < a.vBegin || v > a.vEnd || uLo < std::max(a.uBegin, b.cut.firstColumn(v)) ||
          uHi > std::min(a.uEnd, b.cut.lastColumn(v)))
        continue;
      const std::size_t i = std::size_t(v - a.vBegin) * std::size_t(a.uEnd - a.uBegin + 1) +
                            std::size_t(uLo - a.uBegin);
      return {b.x + i, b.y + i, b.z + i};
    }
    return {};
  }
};

}  // namespace ps::terrain::detail
