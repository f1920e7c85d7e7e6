#include "edit/region_growing.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/input_error.hpp"

namespace ps::edit {

namespace {

// Sorts spans by start and merges overlapping or touching ones.
void mergeSpans(std::vector<Span>& s) {
  std::sort(s.begin(), s.end(), [](const Span& a, const Span& b) { return a.uBegin < b.uBegin; });
  std::size_t out = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (out > 0 && s[i].uBegin <= s[out - 1].uEnd + 1) {
      s[out - 1].uEnd = std::max(s[out - 1].uEnd, s[i].uEnd);
    } else {
      s[out++] = s[i];
    }
  }
  s.resize(out);
}

// Adds the seam twin of column 0 / m where only one of them is present (spans sorted, merged).
void addTwins(std::vector<Span>& s, int m) {
  if (s.empty()) return;
  const bool has0 = s.front().uBegin == 0, hasM = s.back().uEnd == m;
  if (has0 && !hasM) s.push_back({m, m});
  if (hasM && !has0) s.insert(s.begin(), Span{0, 0});
  mergeSpans(s);
}

bool inRun(const ColumnRun& r, int c, int cols) {
  int d = c - r.start;
  if (d < 0) d += cols;
  return d < r.len;
}

bool covered(const std::vector<ColumnRun>& runs, int c, int cols) {
  for (const ColumnRun& r : runs) {
    if (inRun(r, c, cols)) return true;
  }
  return false;
}

// Columns under a run widened by one on each side: its 4-8 neighbourhood in the next row.
ColumnRun neighbourRange(const ColumnRun& s, int cols, bool wraps) {
  if (s.len >= cols) return {0, cols};
  if (wraps) {
    if (s.len + 2 >= cols) return {0, cols};
    return {s.start == 0 ? cols - 1 : s.start - 1, s.len + 2};
  }
  const int a = std::max(0, s.start - 1), b = std::min(cols - 1, s.start + s.len);
  return {a, b - a + 1};
}

// Lat-long chart: a row's inside set is {u : fold(u) <= K_v}; K_v by bisection, cached per row.
struct LatLongOracle {
  const DistanceField& f;
  double r2;
  int m;
  std::vector<int>& halfWidth;  // -2: not computed
  std::size_t& evaluations;

  int rowHalfWidth(int v) const {
    int& k = halfWidth[std::size_t(v)];
    if (k != -2) return k;
    const DistanceField::Row row = f.row(v);
    ++evaluations;
    if (!(f.distance2(row, 0) <= r2)) return k = -1;
    int lo = 0, hi = m / 2;
    ++evaluations;
    if (f.distance2(row, hi) <= r2) return k = hi;
    while (hi - lo > 1) {  // invariant: lo inside, hi outside (the predicate is monotone in k)
      const int mid = lo + (hi - lo) / 2;
      ++evaluations;
      if (f.distance2(row, mid) <= r2) {
        lo = mid;
      } else {
        hi = mid;
      }
    }
    return k = lo;
  }
  bool inside(int v, int c) const { return f.fold(c) <= rowHalfWidth(v); }
  ColumnRun span(int v, int /*c*/) const {
    const int k = rowHalfWidth(v);
    if (2 * k + 1 >= m) return {0, m};
    int s = f.centre().u - k;
    if (s < 0) s += m;
    return {s, 2 * k + 1};
  }
  template <class Push>
  void seeds(int v, const ColumnRun& range, const std::vector<ColumnRun>& found,
             Push&& push) const {
    if (!found.empty() || rowHalfWidth(v) < 0) return;  // one run per row: already found, or none
    // The run is an arc about the centre column: it meets `range` at the centre or at an end.
    const int uc = f.centre().u;
    const int last = (range.start + range.len - 1) % m;
    if (inRun(range, uc, m)) {
      push(uc);
    } else if (inside(v, range.start)) {
      push(range.start);
    } else if (inside(v, last)) {
      push(last);
    }
  }
};

// Any chart: vertex-by-vertex scans of the predicate's values, computed by blocks of a row.
struct GenericOracle {
  const DistanceField& f;
  double r2;
  int m, cols;
  bool wraps, poles;
  RowDistanceBlocks& blocks;

  bool pole(int v) const { return poles && (v == 0 || v == m); }
  bool inside(int v, int c) const { return blocks.at(f, v, pole(v) ? 0 : c) <= r2; }
  // Without a seam or pole rows a row's columns are scanned a block at a time, not looked up one
  // by one (three look-ups a vertex were half of a fill's time on the octahedral chart).
  bool blockScans() const { return !wraps && !poles; }
  // The first column in [from, to) that is outside, else to.
  int firstOutsideRightwards(int v, int from, int to) const {
    for (int c = from; c < to;) {
      const int b = c / RowDistanceBlocks::kBlock, begin = b * RowDistanceBlocks::kBlock;
      const double* d = blocks.block(f, v, b);
      for (const int end = std::min(to, begin + RowDistanceBlocks::kBlock); c < end; ++c)
        if (!(d[c - begin] <= r2)) return c;
    }
    return to;
  }
  // The last column in [0, from] that is outside, else -1.
  int firstOutsideLeftwards(int v, int from) const {
    for (int c = from; c >= 0;) {
      const int b = c / RowDistanceBlocks::kBlock, begin = b * RowDistanceBlocks::kBlock;
      const double* d = blocks.block(f, v, b);
      for (; c >= begin; --c)
        if (!(d[c - begin] <= r2)) return c;
    }
    return -1;
  }
  ColumnRun span(int v, int c) const {
    if (pole(v)) return {0, cols};
    if (blockScans()) {
      const int end = firstOutsideRightwards(v, c + 1, cols),
                start = firstOutsideLeftwards(v, c - 1) + 1;
      return {start, end - start};
    }
    int start = c, len = 1;
    for (int next = c + 1;; ++next) {  // rightwards
      if (len >= cols) break;
      if (next >= cols) {
        if (!wraps) break;
        next -= cols;
      }
      if (!inside(v, next)) break;
      ++len;
    }
    for (int prev = c - 1;; --prev) {  // leftwards
      if (len >= cols) break;
      if (prev < 0) {
        if (!wraps) break;
        prev += cols;
      }
      if (!inside(v, prev)) break;
      start = prev;
      ++len;
    }
    return {start, len};
  }
  template <class Push>
  void seeds(int v, const ColumnRun& range, const std::vector<ColumnRun>& found,
             Push&& push) const {
    if (pole(v)) {
      if (found.empty() && inside(v, 0)) push(0);
      return;
    }
    if (blockScans()) {
      // As below: a covered run is passed at once, an inside run after its seed by a scan.
      for (int c = range.start, end = range.start + range.len; c < end;) {
        const auto run = std::find_if(found.begin(), found.end(),
                                      [&](const ColumnRun& r) { return inRun(r, c, cols); });
        if (run != found.end()) {
          c = run->start + run->len;
        } else if (!inside(v, c)) {
          ++c;
        } else {
          push(c);
          c = firstOutsideRightwards(v, c + 1, end);
        }
      }
      return;
    }
    for (int i = 0; i < range.len; ++i) {
      const int c = (range.start + i) % cols;
      if (covered(found, c, cols) || !inside(v, c)) continue;
      push(c);
      // The rest of this run belongs to the same span.
      while (i + 1 < range.len && inside(v, (range.start + i + 1) % cols)) ++i;
    }
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// RowDistanceBlocks

void RowDistanceBlocks::reset(int rows, int cols, bool wraps, bool poles) {
  for (const int v : rows_) slots_[std::size_t(v)].clear();
  rows_.clear();
  if (slots_.size() != std::size_t(rows)) slots_.assign(std::size_t(rows), {});
  cols_ = cols;
  wraps_ = wraps;
  poles_ = poles;
  values_.clear();
  computed_ = 0;
}

std::int32_t RowDistanceBlocks::compute(const DistanceField& f, int v, int block) {
  const std::int32_t slot = std::int32_t(values_.size() / kBlock);
  const int a = block * kBlock, b = std::min(cols_ - 1, a + kBlock - 1);
  values_.resize(values_.size() + kBlock);
  f.rowDistances2(v, a, b, values_.data() + values_.size() - kBlock);
  computed_ += std::size_t(b - a + 1);
  return slot;
}

bool RowDistanceBlocks::copy(int v, int uFirst, int uLast, double* out) const {
  if (v < 0 || std::size_t(v) >= slots_.size()) return false;
  const std::vector<std::int32_t>& slots = slots_[std::size_t(v)];
  if (slots.empty()) return false;
  const int m = int(slots_.size()) - 1;
  const bool pole = poles_ && (v == 0 || v == m);
  for (int u = uFirst; u <= uLast; ++u) {
    const int c = pole || (wraps_ && u == m) ? 0 : u;
    const std::int32_t slot = slots[std::size_t(c / kBlock)];
    if (slot < 0) return false;
    out[u - uFirst] = values_[std::size_t(slot) * kBlock + std::size_t(c % kBlock)];
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Region

void Region::clear() {
  vBegin_ = 0;
  vEnd_ = -1;
  rowStart_.assign(1, 0);
  spans_.clear();
  halfWidth_.clear();
  vertexCount_ = pointCount_ = 0;
  bounds_ = terrain::VertexBox::none();
  symmetric_ = false;
  centreU_ = 0;
}

void Region::addRow(int v, std::span<const Span> spans, int halfWidth) {
  if (vEnd_ < vBegin_) {
    vBegin_ = v;
    vEnd_ = v - 1;
  }
  while (vEnd_ < v - 1) {
    ++vEnd_;
    rowStart_.push_back(rowStart_.back());
    halfWidth_.push_back(-1);
  }
  spans_.insert(spans_.end(), spans.begin(), spans.end());
  rowStart_.push_back(std::uint32_t(spans_.size()));
  halfWidth_.push_back(halfWidth);
  vEnd_ = v;
}

bool Region::contains(int u, int v) const {
  for (const Span& s : row(v)) {
    if (u >= s.uBegin && u <= s.uEnd) return true;
  }
  return false;
}

void Region::clipRows(int vFirst, int vLast) {
  int a = vLast + 1, z = vFirst - 1;
  for (int v = std::max(vBegin_, vFirst); v <= std::min(vEnd_, vLast); ++v)
    if (!row(v).empty()) a = std::min(a, v), z = std::max(z, v);
  if (a > z) {
    bounds_ = terrain::VertexBox::none();
    return;
  }
  bounds_.vBegin = a, bounds_.vEnd = z;
}

void Region::clipBounds(const terrain::VertexBox& box) {
  terrain::VertexBox b{box.uEnd + 1, box.uBegin - 1, box.vEnd + 1, box.vBegin - 1};
  for (int v = std::max(vBegin_, box.vBegin); v <= std::min(vEnd_, box.vEnd); ++v)
    for (const Span& s : row(v)) {
      const int a = std::max(s.uBegin, box.uBegin), z = std::min(s.uEnd, box.uEnd);
      if (a > z) continue;
      b.uBegin = std::min(b.uBegin, a), b.uEnd = std::max(b.uEnd, z);
      b.vBegin = std::min(b.vBegin, v), b.vEnd = std::max(b.vEnd, v);
    }
  bounds_ = b.uBegin <= b.uEnd ? b : terrain::VertexBox::none();
}

void Region::finish(const core::GridSize& g, bool wrapsU, bool hasPoleRows, bool symmetric,
                    int centreU) {
  const int m = g.m();
  symmetric_ = symmetric;
  centreU_ = centreU;
  vertexCount_ = pointCount_ = 0;
  for (int v = vBegin_; v <= vEnd_; ++v) {
    const auto r = row(v);
    if (r.empty()) continue;
    std::size_t n = 0;
    for (const Span& s : r) n += std::size_t(s.size());
    vertexCount_ += n;
    if (hasPoleRows && (v == 0 || v == m)) {
      pointCount_ += 1;
    } else {
      pointCount_ += n - ((wrapsU && r.front().uBegin == 0 && r.back().uEnd == m) ? 1 : 0);
    }
  }
  if (spans_.empty()) {
    bounds_ = terrain::VertexBox::none();
    return;
  }
  terrain::VertexBox b;
  b.vBegin = vBegin_;
  b.vEnd = vEnd_;
  if (!wrapsU) {
    b.uBegin = m;
    b.uEnd = 0;
    for (const Span& s : spans_)
      b.uBegin = std::min(b.uBegin, s.uBegin), b.uEnd = std::max(b.uEnd, s.uEnd);
    bounds_ = b;
    return;
  }
  // Columns on the circle of m (u = m is column 0): merge the covered arcs and leave out the
  // largest gap.
  std::vector<Span> arcs;
  arcs.reserve(spans_.size());
  for (const Span& s : spans_) {
    if (s.uBegin < m) arcs.push_back({s.uBegin, std::min(s.uEnd, m - 1)});
    if (s.uEnd == m) arcs.push_back({0, 0});
  }
  mergeSpans(arcs);
  int gapLen = arcs.front().uBegin + m - (arcs.back().uEnd + 1);  // around the seam
  int coverStart = arcs.front().uBegin;
  for (std::size_t i = 1; i < arcs.size(); ++i) {
    const int gap = arcs[i].uBegin - arcs[i - 1].uEnd - 1;
    if (gap > gapLen) gapLen = gap, coverStart = arcs[i].uBegin;
  }
  const int len = m - gapLen;
  if (len >= m) {
    b.uBegin = 0, b.uEnd = m;
  } else {
    const int end = coverStart + len - 1;
    if (coverStart == 0 && end == 0) {
      b.uBegin = -1, b.uEnd = 0;  // u = 0 and m (plus m - 1: {0, m} alone has no VertexBox)
    } else if (coverStart == 0) {
      b.uBegin = m, b.uEnd = m + end;  // u = m and 0 .. end (see VertexBox::forEachColumnRange)
    } else if (end >= m) {
      b.uBegin = coverStart - m, b.uEnd = end - m;  // coverStart .. m and 0 .. end - m
    } else {
      b.uBegin = coverStart, b.uEnd = end;
    }
  }
  bounds_ = b;
}

Region Region::fromRectangle(const terrain::VertexBox& r, const core::GridSize& g, bool wrapsU,
                             bool hasPoleRows) {
  Region out;
  out.clear();
  const int m = g.m();
  std::vector<Span> spans;
  for (int v = std::max(0, r.vBegin); v <= std::min(m, r.vEnd); ++v) {
    spans.clear();
    if (hasPoleRows && (v == 0 || v == m)) {
      spans.push_back({0, m});
    } else {
      if (wrapsU) {
        r.forEachColumnRange(g, [&](int a, int b) { spans.push_back({a, b}); });
        mergeSpans(spans);
        addTwins(spans, m);
      } else if (std::max(0, r.uBegin) <= std::min(m, r.uEnd)) {
        spans.push_back({std::max(0, r.uBegin), std::min(m, r.uEnd)});  // no seam: clipped
      }
    }
    out.addRow(v, spans);
  }
  out.finish(g, wrapsU, hasPoleRows, false, 0);
  return out;
}

// ---------------------------------------------------------------------------------------------
// RegionGrower

template <class Oracle>
void RegionGrower::fill(const Oracle& oracle, const core::GridSize& g, bool wraps,
                        core::GridPoint seed) {
  const int m = g.m(), cols = wraps ? m : m + 1;
  stack_.clear();
  stack_.push_back({seed.v, seed.u});
  while (!stack_.empty()) {
    const auto [v, c] = stack_.back();
    stack_.pop_back();
    auto& runs = rowSpans_[std::size_t(v)];
    if (covered(runs, c, cols) || !oracle.inside(v, c)) continue;
    if (runs.empty()) touched_.push_back(v);
    const ColumnRun s = oracle.span(v, c);
    runs.push_back(s);
    const ColumnRun range = neighbourRange(s, cols, wraps);
    for (const int nv : {v - 1, v + 1}) {
      if (nv < 0 || nv > m) continue;
      oracle.seeds(nv, range, rowSpans_[std::size_t(nv)], [&](int col) {
        stack_.push_back({nv, col});
      });
    }
  }
}

void RegionGrower::emit(const core::GridSize& g, bool wraps, bool poles, bool symmetric,
                        int centreU, Region& out) {
  const int m = g.m();
  out.clear();
  std::sort(touched_.begin(), touched_.end());
  for (const int v : touched_) {
    auto& runs = rowSpans_[std::size_t(v)];
    scratch_.clear();
    for (const ColumnRun& r : runs) {
      if (!wraps) {
        scratch_.push_back({r.start, r.start + r.len - 1});
      } else if (r.len >= m) {
        scratch_.push_back({0, m});
      } else {
        const int end = r.start + r.len - 1;
        if (end < m) {
          scratch_.push_back({r.start, end});
        } else {
          scratch_.push_back({r.start, m});  // u = m is column 0
          if (end > m) scratch_.push_back({0, end - m});
        }
      }
    }
    mergeSpans(scratch_);
    if (wraps) addTwins(scratch_, m);
    if (poles && (v == 0 || v == m)) scratch_.assign(1, Span{0, m});
    out.addRow(v, scratch_, symmetric ? std::min(halfWidth_[std::size_t(v)], m / 2) : -1);
    runs.clear();
  }
  touched_.clear();
  out.finish(g, wraps, poles, symmetric, centreU);
}

void RegionGrower::grow(const DistanceField& field, double radius, Region& out) {
  if (!std::isfinite(radius) || !(radius > 0.0)) {
    throw core::InputError("radius of deformation " + std::to_string(radius) +
                           " m must be finite and > 0");
  }
  const core::GridSize g = field.grid();
  const int m = g.m();
  const core::Chart& chart = field.chart();
  const bool wraps = chart.wrapsU(), poles = chart.hasPoleRows();
  const double r2 = radius * radius;
  if (rowSpans_.size() != std::size_t(m) + 1) rowSpans_.assign(std::size_t(m) + 1, {});
  touched_.clear();
  evaluations_ = 0;
  const core::GridPoint seed = field.centre();
  latLongGrow_ = field.latLong() != nullptr;
  if (field.latLong()) {
    halfWidth_.assign(std::size_t(m) + 1, -2);
    const LatLongOracle oracle{field, r2, m, halfWidth_, evaluations_};
    fill(oracle, g, true, seed);
    emit(g, true, true, true, seed.u, out);
  } else {
    const int cols = wraps ? m : m + 1;
    blocks_.reset(m + 1, cols, wraps, poles);
    const GenericOracle oracle{field, r2, m, cols, wraps, poles, blocks_};
    fill(oracle, g, wraps, seed);
    const bool glued = chart.gluesSidesBeyondSeam();
    if (glued) fillAcrossGluedSides(oracle, chart);
    evaluations_ = blocks_.computed();
    emit(g, wraps, poles, false, seed.u, out);
    if (glued) {
      // The dirty box: the region's vertices in the centre's part of the grid (closed; a half
      // for each flip the chart's images use); the terrain covers the rest by that box's images
      // (terrain::gluedImages). A u seam's columns stay as emit() wrapped them.
      const core::Chart::Flips f = chart.imageFlips();
      const bool left = 2 * seed.u <= m, low = 2 * seed.v <= m;
      const int v0 = f.v ? (low ? 0 : m / 2) : 0, v1 = f.v ? (low ? m / 2 : m) : m;
      if (f.u) {
        out.clipBounds({left ? 0 : m / 2, left ? m / 2 : m, v0, v1});
      } else {
        out.clipRows(v0, v1);
      }
    }
  }
}

template <class Oracle>
void RegionGrower::fillAcrossGluedSides(const Oracle& oracle, const core::Chart& chart) {
  // The fill stops at the grid's sides (a u seam it crosses itself); a side vertex it reached
  // is also its twins, from which the fill goes on into the grid beyond the side (a mirrored
  // side's other half, the torus's other end of the v seam), until no twin is left outside.
  const int m = chart.grid().m();
  const bool wraps = chart.wrapsU();
  const int cols = wraps ? m : m + 1;  // on a u seam, column m is column 0
  std::vector<core::GridPoint> seeds;
  auto twinsOf = [&](int u, int v) {
    core::GridPoint t[4];
    const int n = chart.twins(u, v, t);
    for (int k = 0; k < n; ++k) {
      const int c = wraps && t[k].u == m ? 0 : t[k].u;
      if (!covered(rowSpans_[std::size_t(t[k].v)], c, cols)) seeds.push_back({c, t[k].v});
    }
  };
  for (bool more = true; more;) {
    seeds.clear();
    for (const int v : {0, m})
      for (const ColumnRun& r : rowSpans_[std::size_t(v)])
        for (int k = 0; k < r.len; ++k) twinsOf((r.start + k) % cols, v);
    if (!wraps) {
      for (const int v : std::vector<int>(touched_)) {
        const auto& runs = rowSpans_[std::size_t(v)];
        if (covered(runs, 0, cols)) twinsOf(0, v);
        if (covered(runs, m, cols)) twinsOf(m, v);
      }
    }
    more = false;
    for (const core::GridPoint& p : seeds) {
      if (covered(rowSpans_[std::size_t(p.v)], p.u, cols)) continue;
      fill(oracle, chart.grid(), wraps, p);
      more = true;
    }
  }
}

std::size_t bruteForceRegion(const DistanceField& field, double radius,
                             std::vector<std::uint8_t>* mask) {
  const core::GridSize g = field.grid();
  const int m = g.m();
  const double r2 = radius * radius;
  if (mask) mask->assign(g.count(), 0);
  std::uint8_t* out = mask ? mask->data() : nullptr;
  std::size_t count = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : count)
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      if (field.distance2(u, v) <= r2) {
        ++count;
        if (out) out[g.index(u, v)] = 1;
      }
    }
  }
  return count;
}

}  // namespace ps::edit
