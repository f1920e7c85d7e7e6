#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/chart.hpp"
#include "core/huge_page_allocator.hpp"
#include "terrain/bound_code.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::terrain {

namespace detail {
struct PositionBoxes;
}

// How the nested per-vertex error is derived (docs/ERROR-BOUNDS.md compares them).
enum class ErrorRule {
  // Paper 003 / ROAM: eps(v) = max over children eps(c) + |P(v) - (P(b0) + P(b1)) / 2|, with the
  // midpoint error taken as a 3D vector length (heights displace radially, the chart is curved).
  kWedgie,
  // Ours: for diamonds up to kExactMaxHalfSize the exact maximum 3D deviation of the
  // full-resolution vertices from the diamond's two triangles (maxed with the children's, to
  // stay nested), the wedgie rule above that.
  kHybridExact,
};

// What a build computes. A whole-planet export at a fixed error reads only the errors; the
// radii (view-dependent projection and culling) cost as much again to build, so an export of a
// heightmap file skips them. A terrain built without radii cannot be tessellated for a view.
enum class BoundsContent { kErrorsAndRadii, kErrorsOnly };

std::string toString(ErrorRule rule);
ErrorRule errorRuleFromString(const std::string& s);  // throws core::InputError

// For every split vertex v of the 4-8 hierarchy two nested bounds:
//   error(v)  >= the largest 3D distance between a full-resolution vertex inside v's diamond and
//                the point the diamond's two triangles put it at (parameter-space barycentric
//                interpolation of the corners' 3D positions);
//   radius(v) >= the largest distance from P(v) to a full-resolution vertex inside the diamond.
// Nested: error(child) <= error(parent), radius(child) + |P(child) - P(parent)| <= radius(parent),
// across the seam too (twins hold the same, combined values). Grid corners store 0.
// The two codes of one vertex sit side by side: the tessellator reads both for every triangle it
// visits, so they should cost one cache miss, not two.
struct BoundCodes {
  std::uint16_t error = 0;
  std::uint16_t radius = 0;
  bool operator==(const BoundCodes&) const = default;
};

// A split vertex's height and bounds side by side: what the tessellator reads per visit.
struct LatticeEntry {
  float height = 0;
  BoundCodes codes;
  // The largest error code among the vertex's children in the grid, which are the split
  // vertices of the triangles its diamond's two triangles split into. Their balls lie inside
  // this vertex's ball (nesting), so when this error would not split them seen from this ball,
  // the tessellator emits them without visiting them.
  std::uint16_t childError = 0;
  bool operator==(const LatticeEntry&) const = default;
};

class ErrorBounds {
 public:
  using CodeArray = std::vector<BoundCodes, core::HugePageAllocator<BoundCodes>>;
  using Lattice = std::vector<LatticeEntry, core::HugePageAllocator<LatticeEntry>>;

  static constexpr int kExactMaxHalfSize = 4;

  ErrorBounds() = default;

  void build(const core::Chart& chart, std::span<const float> heights, ErrorRule rule,
             BoundsContent content = BoundsContent::kErrorsAndRadii);
  // Recomputes only the vertices whose bounds can depend on heights inside `dirty`, level by
  // level up to the root. Bit-for-bit equal to build() on the same heights.
  void update(const core::Chart& chart, std::span<const float> heights, const VertexBox& dirty);
  // The same over several dirty rectangles at once (a chart that folds its sides: an edit's
  // box and its images, terrain::gluedImages).
  void update(const core::Chart& chart, std::span<const float> heights,
              std::span<const VertexBox> dirty);
  // The same over rectangles with their corners cut (CutBox: every changed height inside
  // one of them). On a chart with a u seam the cuts are not used (its regions' columns wrap).
  void update(const core::Chart& chart, std::span<const float> heights,
              std::span<const CutBox> dirty);

  ErrorRule rule() const { return rule_; }
  bool hasRadii() const { return content_ == BoundsContent::kErrorsAndRadii; }
  float error(std::size_t index) const { return BoundCode::decode(codes_[index].error); }
  float radius(std::size_t index) const { return BoundCode::decode(codes_[index].radius); }
  const CodeArray& codes() const { return codes_; }

  // Every split vertex of half-size >= 2^kLatticeShift lies on every 2^kLatticeShift-th row and
  // column. The tessellator visits those (most of a view's mesh) in a scattered order, where in
  // the full arrays each visit was two cache misses pages apart (heights and codes, 512 MiB at
  // 8193²). Packed here with their heights, 1/64 of the grid (8 MiB at 8193²), they stay in the
  // last-level cache. The lattice is stored level by level, each level's vertices in a dense
  // array of their own (a pyramid): the tessellator reads one level at a time, and a level of
  // half-size s holds 1/s² of the grid, so its vertices share cache lines with their neighbours
  // on the level (in one row-major lattice, a level of half-size 16 used a quarter of each line
  // it touched, 32 an eighth). Empty without radii (exports).
  static constexpr int kLatticeShift = 3;
  const Lattice& lattice() const { return lattice_; }
  // One level's packed vertices: vertex (u, v) of the level is at(u, v).
  struct LatticeLevel {
    const LatticeEntry* entries = nullptr;
    std::size_t width = 0;
    int rowShift = 0, columnShift = 0;
    const LatticeEntry& at(int u, int v) const {
      return entries[std::size_t(v >> rowShift) * width + std::size_t(u >> columnShift)];
    }
  };
  // The level of half-size s (a power of two, 2^kLatticeShift <= s < m), centres or edges.
  LatticeLevel latticeLevel(int halfSize, bool centre) const;
  // Entry of lattice vertex (u, v), any level; not a grid corner (corners split nothing).
  std::size_t latticeIndex(int u, int v) const;
  // Copies of one half of the codes, for comparisons in tests and tools.
  std::vector<std::uint16_t> errorCodes() const;
  std::vector<std::uint16_t> radiusCodes() const;
  std::size_t bytes() const {
    return codes_.size() * sizeof(BoundCodes) + lattice_.size() * sizeof(LatticeEntry);
  }

  // Vertices recomputed by the last update() (for benchmarks: the work done).
  std::size_t lastUpdateVertexCount() const { return lastUpdateCount_; }

 private:
  // One level's vertices in `regions`, which must not overlap (their rows run on the team
  // together). `gluedRegions`: on a chart that glues its sides beyond a u seam (core::Chart::
  // gluesSidesBeyondSeam), the level's regions whose side vertices combine with their twins
  // after the regions' rows (null: none). `boxes`: positions computed ahead, read instead of
  // computing them (null: none).
  template <class ChartT>
  void computeLevel(const ChartT& chart, std::span<const float> heights, int level,
                    std::span<const CutBox> regions,
                    const std::vector<CutBox>* gluedRegions = nullptr,
                    const detail::PositionBoxes* boxes = nullptr);

  ErrorRule rule_ = ErrorRule::kHybridExact;
  BoundsContent content_ = BoundsContent::kErrorsAndRadii;
  CodeArray codes_;
  Lattice lattice_;
  // Where each lattice level starts in lattice_, by log2(half-size) and kind (centre = 1).
  std::vector<std::array<std::size_t, 2>> latticeOffsets_;
  int gridM_ = 0;
  std::size_t lastUpdateCount_ = 0;
};

}  // namespace ps::terrain
