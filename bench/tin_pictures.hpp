#pragma once
// Pictures of `bench export`'s TINs: wireframes over hill shading (docs/images/).
#include <string>
#include <vector>

#include "bench/bench_export.hpp"
#include "tin/overlay.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::bench {

// Paper 001's picture: the control map (white: MinError) beside the TIN it gives, wireframe over
// hill shading, on a window across the control region's edge (a disc at the tile's centre).
void writeControlMapPicture(const Heightmap& h, const std::vector<bool>& inside, const tin::Tin& t,
                            const std::string& path);

// A road stitched (left) and stenciled (right) into the same terrain: terrain edges thin, the
// road's triangles filled, on a window around the road.
void writeOverlayPicture(const Heightmap& h, const tin::OverlayResult& stitched,
                         const tin::OverlayResult& stenciled, const std::string& path);

}  // namespace ps::bench
