#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ps::io {

struct FillReport {
  std::size_t filled = 0;  // pixels that were holes
  int sweeps = 0;          // relaxation sweeps run
  double lastChange = 0;   // largest update in the last sweep (metres)
};

// Fills the pixels marked in `hole` (w x h, row-major) with the harmonic (Laplace)
// interpolation of their surroundings: every filled pixel ends as the mean of its 4 neighbours
// (fewer at an image edge), so the fill is smooth, follows the slopes around the hole's rim and
// never goes above or below the rim's highest and lowest value. Solved by successive
// over-relaxation over the hole pixels only, started from each hole pixel's nearest valid
// value, until no pixel moves by more than 1e-4 of the data's range (or a sweep cap).
// wrapX: the left and right columns are neighbours (a global equirectangular image).
// Requires at least one valid pixel.
FillReport fillHoles(std::vector<float>& values, int w, int h,
                     const std::vector<std::uint8_t>& hole, bool wrapX);

}  // namespace ps::io
