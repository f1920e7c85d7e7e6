#pragma once
// The planet board and tool cube rows of `planetsculpt bench track` (bench_track_board.cpp).
#include <ostream>

#include "bench/bench.hpp"

namespace ps::bench {

// `singleMarkerMs`: the single-marker default detector's median time per frame on the sweep,
// measured in the same run (0: not measured; the ratio is then left out).
void benchTrackBoards(const BenchOptions& options, double singleMarkerMs, std::ostream& out);

}  // namespace ps::bench
