#pragma once
// Which vertices of one level of ErrorBounds a region holds, and how they are shared among
// threads (error_bounds.cpp includes this; nothing else should): the level's rows inside the
// region, its column ranges (two across the seam), bands of rows as work items, and their work.
#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "core/grid.hpp"
#include "terrain/diamond.hpp"
#include "terrain/error_bounds.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::terrain::detail {

struct LevelPlan {
  // Levels 0-5 go to the row kernels in bands of kBand rows, chunk by chunk across the band, so
  // that neighbouring rows share the rows of positions they read (BoundKernels::forgetRows at
  // the start of an item: nothing is shared across items, whose order is the scheduler's).
  static constexpr std::size_t kBand = 8;
  // The work (vertices, all of a level's regions together) from which the level goes to the
  // team. Small regions (a typical edit near the fine levels) stay on this thread: waking the
  // team costs more than the work, and much more when the machine is busy. About 2,000
  // vertices (0.1-0.2 ms of work) pays: at 20,000 the pole's level 6 (17,000 vertices, 1.7 ms)
  // and most levels of a 600 km edit elsewhere ran on one thread (bench deform: 300 km polar
  // cap 19.5-21.5 -> 17.5-20.2 ms, latitude 30 / 600 km 6.6-7.7 -> 5.2-6.0 ms).
  static constexpr double kParallelWork = 2000.0;
  // A vertex of the scalar path (above the row kernels' levels) costs about four of the
  // kernels': it computes most of the positions it reads (the octahedral chart's at about 60 ns
  // each). Level 6 of a 600 km edit on the octahedral chart, 1,800 vertices, took 0.46 ms on
  // one thread when counted as kernel vertices.
  static constexpr double kScalarVertexWork = 4.0;

  LevelPlan(const core::GridSize& g, int level, const CutBox& cutBox)
      : m(g.m()),
        s(levelHalfSize(level)),
        centre(levelIsCentre(level)),
        kernelLevel(s <= ErrorBounds::kExactMaxHalfSize),
        band(kernelLevel ? kBand : 1),
        cut(cutBox.cut) {
    const VertexBox& region = cutBox.box;
    const int vFirst = ((region.vBegin + s - 1) / s) * s;
    for (int v = vFirst; v <= region.vEnd; v += s) {
      const bool vOdd = ((v / s) & 1) != 0;
      if (centre && !vOdd) continue;  // centre vertices sit on odd rows only
      if (cut.firstColumn(v) > cut.lastColumn(v)) continue;
      rows.push_back(v);
    }
    // A region across the seam is two column ranges; one loop over (row, range) items keeps
    // both cores on one team instead of two fork-joins per level, each with half the work.
    region.forEachColumnRange(g, [&](int uA, int uB) {
      ranges[rangeCount++] = {uA, uB};
      for (int v : rows) {
        const auto [a, b] = clip(v, {uA, uB});
        if (a <= b)
          work += double(b - a + 1) / double(2 * s) * (kernelLevel ? 1.0 : kScalarVertexWork);
      }
    });
    items = (rows.size() + band - 1) / band * rangeCount;
  }

  // A column range's part on row v within the cut (first > last: none).
  std::pair<int, int> clip(int v, std::pair<int, int> range) const {
    return {std::max(range.first, cut.firstColumn(v)), std::min(range.second, cut.lastColumn(v))};
  }

  // The first column of the level on row v at or after uA.
  int firstColumn(int v, int uA) const {
    // On an odd row (v/s odd), edge vertices have u/s even and centres u/s odd; on an even row
    // only edge vertices, u/s odd.
    const bool wantUOdd = centre || ((v / s) & 1) == 0;
    int u = ((uA + s - 1) / s) * s;
    if ((((u / s) & 1) != 0) != wantUOdd) u += s;
    return u;
  }
  // Work item `item`: rows [rowBegin, rowEnd) within column range `range`.
  std::size_t rowBegin(std::size_t item) const { return (item / rangeCount) * band; }
  std::size_t rowEnd(std::size_t item) const {
    return std::min(rows.size(), rowBegin(item) + band);
  }
  std::pair<int, int> range(std::size_t item) const { return ranges[item % rangeCount]; }

  int m;
  int s;             // the level's half-size
  bool centre;       // centre vertices (odd levels) or edge vertices
  bool kernelLevel;  // the row kernels take the rows' inner vertices
  std::size_t band;  // rows per work item
  Diagonals cut;     // the region's corners cut off (open on charts with a u seam)
  std::vector<int> rows;
  std::array<std::pair<int, int>, 2> ranges{};
  std::size_t rangeCount = 0;
  std::size_t items = 0;
  double work = 0;  // about the vertices computed
};

}  // namespace ps::terrain::detail
