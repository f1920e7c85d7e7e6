#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/grid.hpp"
#include "edit/distance_field.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::edit {

// An inclusive run of grid columns of one row: 0 <= uBegin <= uEnd <= m.
struct Span {
  int uBegin = 0, uEnd = -1;
  int size() const { return uEnd - uBegin + 1; }
  friend bool operator==(const Span&, const Span&) = default;
};

// A run of columns in the fill's own coordinates: `cols` distinct columns (m on a seamed chart,
// where u = m is column 0), start in [0, cols), len in [1, cols]; circular on a seamed chart.
struct ColumnRun {
  int start = 0, len = 0;
};

// A set of grid vertices stored as sorted, disjoint column spans per row, rows vBegin..vEnd.
// Seam twins are explicit: when a region holds column u = 0 of a row it also holds u = m. A pole
// row in a region is always whole (its m + 1 entries are one point). Regions grown on the
// lat-long chart have at most two spans per row (one circular interval split at the seam, or a
// span plus the lone twin u = m), so even a 2-million-vertex polar cap costs a few KB.
class Region {
 public:
  bool empty() const { return spans_.empty(); }
  int vBegin() const { return vBegin_; }
  int vEnd() const { return vEnd_; }
  std::span<const Span> row(int v) const {
    if (v < vBegin_ || v > vEnd_) return {};
    const std::size_t r = std::size_t(v - vBegin_);
    return {spans_.data() + rowStart_[r], spans_.data() + rowStart_[r + 1]};
  }
  std::size_t spanCount() const { return spans_.size(); }
  // Grid entries, counting seam twins and every entry of a pole row (the paper's count).
  std::size_t vertexCount() const { return vertexCount_; }
  // Distinct points on the sphere (a twin pair and a pole row count once).
  std::size_t pointCount() const { return pointCount_; }
  bool contains(int u, int v) const;
  // The smallest seam-wrapped rectangle holding every vertex (the edit's dirty region). On a
  // chart that glues its sides beyond a u seam: the box of the vertices in the centre's part of
  // the grid (the octahedral chart's quadrant, the torus's half in v), whose images
  // (terrain::gluedImages) hold the rest (RegionGrower::grow sets it).
  const terrain::VertexBox& bounds() const { return bounds_; }
  // Makes bounds() the box of the region's vertices within `box`.
  void clipBounds(const terrain::VertexBox& box);
  // Keeps bounds()' columns (seam-wrapped) and makes its rows those of the region's rows within
  // [vFirst, vLast] that hold vertices.
  void clipRows(int vFirst, int vLast);

  // Regions grown on the lat-long chart are symmetric about the centre column: row v holds
  // exactly the vertices whose folded column distance from centreU() is <= halfWidth(v)
  // (halfWidth >= m/2: the whole row; < 0: none).
  bool symmetric() const { return symmetric_; }
  int centreU() const { return centreU_; }
  int halfWidth(int v) const { return halfWidth_[std::size_t(v - vBegin_)]; }

  template <class F>
  void forEachSpan(F&& f) const {  // f(v, uBegin, uEnd)
    for (int v = vBegin_; v <= vEnd_; ++v) {
      for (const Span& s : row(v)) f(v, s.uBegin, s.uEnd);
    }
  }

  // Building: clear(), then addRow() in increasing v (spans sorted, disjoint, twins included),
  // then finish(). Rows skipped between added rows are empty.
  void clear();
  void addRow(int v, std::span<const Span> spans, int halfWidth = -1);
  void finish(const core::GridSize& g, bool wrapsU, bool hasPoleRows, bool symmetric, int centreU);

  // A whole rectangle (for tools that declare a rectangular footprint).
  static Region fromRectangle(const terrain::VertexBox& r, const core::GridSize& g, bool wrapsU,
                              bool hasPoleRows);

 private:
  int vBegin_ = 0, vEnd_ = -1;
  std::vector<std::uint32_t> rowStart_{0};
  std::vector<Span> spans_;
  std::vector<int> halfWidth_;
  std::size_t vertexCount_ = 0, pointCount_ = 0;
  terrain::VertexBox bounds_;
  bool symmetric_ = false;
  int centreU_ = 0;
};

// The distance predicate's values by blocks of a row, each block computed once (with
// DistanceField::rowDistances2, the chart's vectorised row positions) until reset(): the fill
// on charts other than lat-long asks for a vertex several times (its span, then the seeds of
// the rows above and below).
class RowDistanceBlocks {
 public:
  static constexpr int kBlock = 64;
  // Forgets every block; rows 0 .. rows - 1, columns 0 .. cols - 1 (on a u seam, cols = m and
  // grid column m is column 0; with pole rows, a pole row's every vertex is its column 0).
  void reset(int rows, int cols, bool wraps, bool poles);
  double at(const DistanceField& f, int v, int c) { return block(f, v, c / kBlock)[c % kBlock]; }
  // Row v's distances of columns block * kBlock .. + kBlock - 1, computed if not yet (valid
  // until the next block is computed).
  const double* block(const DistanceField& f, int v, int block) {
    std::vector<std::int32_t>& slots = slots_[std::size_t(v)];
    if (slots.empty()) {
      slots.assign(std::size_t((cols_ + kBlock - 1) / kBlock), -1);
      rows_.push_back(v);
    }
    std::int32_t& slot = slots[std::size_t(block)];
    if (slot < 0) slot = compute(f, v, block);
    return values_.data() + std::size_t(slot) * kBlock;
  }
  // Distances computed since reset().
  std::size_t computed() const { return computed_; }
  // Row v's distances for grid columns uFirst .. uLast into out[u - uFirst], bit for bit
  // DistanceField::rowDistances2's, when every block holding them was computed since reset()
  // (true); false otherwise (out partly written). Safe from several threads at once.
  bool copy(int v, int uFirst, int uLast, double* out) const;

 private:
  std::int32_t compute(const DistanceField& f, int v, int block);

  int cols_ = 0;
  bool wraps_ = false, poles_ = false;
  std::vector<std::vector<std::int32_t>> slots_;  // per row, per block: its index in values_
  std::vector<int> rows_;                         // the rows with slots
  std::vector<double> values_;
  std::size_t computed_ = 0;
};

// Region growing (paper 003, section 6.3) as a scanline flood fill: starting from the centre
// vertex of `field`, a row's maximal run of vertices with distance2 <= radius^2 becomes a span,
// and the columns under a span widened by one on each side (its 4-8 neighbourhood) are scanned
// in the rows above and below for seeds of further spans. Longitude wraps across u = 0 / u = m
// (the paper's border treatment: a seam vertex and its twin are one vertex), latitude stops at
// the poles, and a pole row is a single point that neighbours every vertex of the next row.
//
// On the lat-long chart a row's inside set is one interval about the centre column (the
// predicate is monotone in the folded column distance, see DistanceField), so a span is found by
// bisection and a seed by an interval test: the fill costs O(rows * log m), not O(vertices). The
// result equals the brute-force set {every vertex with distance2 <= radius^2} exactly, because
// that set is connected: the centre column of a row is its nearest vertex, and along the centre
// meridian d^2 grows strictly with the latitude difference (the row-to-row increment, at least
// R^2 (pi/m)^2, is ~1e7 times the rounding error). Tests check the equality for centres at the
// poles, the seam and near the poles and for radii from below one cell to the planet's diameter.
// On other charts the same fill scans vertex by vertex (the predicate's values by blocks of a
// row: RowDistanceBlocks) and returns the connected component of the centre; on a chart that
// glues its sides beyond a u seam (the octahedral chart's folds, the torus's v seam) it goes on
// from the twins of the side vertices it reached, so the component is the surface's, across the
// glued sides.
class RegionGrower {
 public:
  // Throws core::InputError for a radius that is not finite and > 0.
  void grow(const DistanceField& field, double radius, Region& out);

  // Predicate evaluations of the last grow() (work measure for tests and benchmarks; on charts
  // other than lat-long the distances computed, whole blocks of a row).
  std::size_t lastEvaluations() const { return evaluations_; }
  // The distances the last grow() computed (every vertex of its region's among them), for the
  // tool that acts on the region; null after a grow on the lat-long chart (its distances are
  // per row and column distance, as cheap to compute again).
  const RowDistanceBlocks* distances() const { return latLongGrow_ ? nullptr : &blocks_; }

 private:
  template <class Oracle>
  void fill(const Oracle& oracle, const core::GridSize& g, bool wraps, core::GridPoint seed);
  void emit(const core::GridSize& g, bool wraps, bool poles, bool symmetric, int centreU,
            Region& out);
  template <class Oracle>
  void fillAcrossGluedSides(const Oracle& oracle, const core::Chart& chart);

  std::vector<std::vector<ColumnRun>> rowSpans_;
  std::vector<int> touched_;
  std::vector<std::pair<int, int>> stack_;
  std::vector<int> halfWidth_;  // lat-long: per row, -2 = not computed yet
  std::vector<Span> scratch_;
  RowDistanceBlocks blocks_;  // other charts
  bool latLongGrow_ = true;
  std::size_t evaluations_ = 0;
};

// The brute-force set: every vertex tested (tests and benchmarks). Returns the count of grid
// entries and, when `mask` is non-null, marks them (index = v * side + u).
std::size_t bruteForceRegion(const DistanceField& field, double radius,
                             std::vector<std::uint8_t>* mask = nullptr);

}  // namespace ps::edit
