#pragma once
// `bench occlusion`'s hand row on the shipped demo (bench_occlusion_hand_demo.cpp).
#include <ostream>

#include "bench/bench.hpp"
#include "tracking/hand_mask.hpp"

namespace ps::bench {

// The demo's frames tracked as `demo` tracks them, the hand mask made and cleared over the
// tracked tool as the demo's AR frames are (replay::HandOcclusion + render::occludeByHand),
// against what the demo's truth has in front of the planet: one JSON row.
void benchOcclusionHandDemo(const BenchOptions& options, const tracking::HandMaskConfig& config,
                            std::ostream& out);

}  // namespace ps::bench
