#pragma once
#include <span>

#include "core/chart.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::edit {

// Writes height h at grid vertex (u, v) and at every grid entry that is the same point: the seam
// twin (u = 0 <-> u = m) on a seamed chart, the whole row at a pole, a glued side's twins
// (core::Chart::twins: a folded side's mirror, the torus's rows v = 0 and m, its corners).
void applyToVertex(const core::Chart& chart, std::span<float> heights, int u, int v, float h);

// Makes the grid entries of `region` that are one point agree: u = m takes u = 0's height on
// every row of the region that touches the seam, a pole row in the region takes its u = 0
// height everywhere, and on a chart that glues its sides beyond a u seam (mirrored sides, the
// torus's v seam) the region's side vertices give their height to their twins. O(rows + m). The
// edit pipeline runs it after every tool.
void enforceConsistency(const core::Chart& chart, std::span<float> heights,
                        const terrain::VertexBox& region);

}  // namespace ps::edit
