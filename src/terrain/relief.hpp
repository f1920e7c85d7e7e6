#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/chart.hpp"
#include "core/grid.hpp"

namespace ps::terrain {

struct ReliefParams {
  std::uint64_t seed = 1;
  double amplitudeMetres = 8000.0;  // heights stay within [-amplitude, +amplitude]
  int octaves = 0;  // 0: choose from the grid (enough to resolve ~2 cells, at most 14)
};

// The octave count generateRelief uses for `grid`: params.octaves when it is non-zero, otherwise
// enough octaves that the finest one still spans about two cells. Throws InputError like
// generateRelief for bad params.
int reliefOctaves(const core::GridSize& grid, const ReliefParams& params);

// Heights in metres for every vertex of `chart`'s grid (index = grid().index(u, v)), computed from
// the vertex's 3D unit direction only, so seam twins and pole rows get bitwise-identical values.
// Earth-like: fBm continents with shelves and ocean basins, ridged mountain ranges on land, detail
// everywhere, all softly clamped into [-amplitude, +amplitude]. Deterministic for a seed whatever
// the thread count, and across machines for builds without FMA contraction (the x86-64 default):
// per vertex only IEEE + - * / run, no libm. Uses OpenMP over rows. `progress` (may be empty) is
// called with a fraction in [0, 1] now and then, from the calling thread only; an exception it
// throws stops the run and comes out of generateRelief.
// Throws core::InputError for amplitude <= 0 or non-finite, octaves < 0 or > 20.
std::vector<float> generateRelief(const core::Chart& chart, const ReliefParams& params,
                                  const std::function<void(double)>& progress = {});

// The height generateRelief gives (before rounding to float) at a unit direction, with an explicit
// octave count in [1, 20] (see reliefOctaves); params.octaves is ignored.
double reliefAt(const Eigen::Vector3d& unitDirection, const ReliefParams& params, int octaves);

}  // namespace ps::terrain
