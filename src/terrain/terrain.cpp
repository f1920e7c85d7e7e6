#include "terrain/terrain.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <sstream>
#include <utility>

#include "core/input_error.hpp"

namespace ps::terrain {

namespace {
std::uint64_t nextRevision() {
  static std::atomic<std::uint64_t> counter{1};
  return counter.fetch_add(1);
}

std::string at(int u, int v) {
  return "vertex (u=" + std::to_string(u) + ", v=" + std::to_string(v) + ")";
}
}  // namespace

void Terrain::validateHeights(const core::Chart& chart, std::span<const float> h) {
  const core::GridSize g = chart.grid();
  if (h.size() != g.count()) {
    throw core::InputError("got " + std::to_string(h.size()) + " heights, a " + g.label() +
                           " grid needs " + std::to_string(g.count()));
  }
  const double limit = chart.heightLimit();
  const int m = g.m();
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const float x = h[g.index(u, v)];
      if (!std::isfinite(x)) {
        std::ostringstream os;
        os << "height at " << at(u, v) << " is " << x << ": heights must be finite";
        throw core::InputError(os.str());
      }
      if (std::abs(double(x)) > limit) {
        std::ostringstream os;
        os << "height " << x << " m at " << at(u, v) << " exceeds the limit of +-" << limit
           << " m (the chart's height limit)";
        throw core::InputError(os.str());
      }
    }
  }
  if (chart.wrapsU()) {
    for (int v = 0; v <= m; ++v) {
      if (h[g.index(0, v)] != h[g.index(m, v)]) {
        throw core::InputError("seam twins differ: height at " + at(0, v) + " != " + at(m, v) +
                               "; u = 0 and u = m are the same meridian");
      }
    }
  }
  if (chart.hasPoleRows()) {
    for (int v : {0, m}) {
      for (int u = 1; u <= m; ++u) {
        if (h[g.index(u, v)] != h[g.index(0, v)]) {
          throw core::InputError("pole row v = " + std::to_string(v) +
                                 " is not one point: height at " + at(u, v) + " differs from " +
                                 at(0, v));
        }
      }
    }
  }
  // Whatever else the chart glues (core::Chart::canonical): the grid's border vertices hold
  // their canonical vertex's height.
  for (int k = 0; k <= m; ++k) {
    for (const auto& [u, v] :
         {std::pair{k, 0}, std::pair{k, m}, std::pair{0, k}, std::pair{m, k}}) {
      const core::GridPoint c = chart.canonical(u, v);
      if (h[g.index(u, v)] != h[g.index(c.u, c.v)]) {
        throw core::InputError("grid vertices at one point differ: height at " + at(u, v) + " != " +
                               at(c.u, c.v) + " (the " + chart.name() + " chart glues them)");
      }
    }
  }
}

Terrain::Terrain(std::shared_ptr<const core::Chart> chart, std::vector<float> heights,
                 ErrorRule rule, BoundsContent content)
    : chart_(std::move(chart)) {
  if (!chart_) throw core::InputError("terrain needs a chart");
  validateHeights(*chart_, heights);
  heights_.assign(heights.begin(), heights.end());
  heights = {};
  bounds_.build(*chart_, heights_, rule, content);
  refreshHeightRange();
  revision_ = nextRevision();
  oldestKnown_ = revision_;
}

void Terrain::refreshHeightRange() {
  // Eight independent lanes the compiler turns into vector min/max (heights are finite, so the
  // order of comparisons cannot change the result); std::minmax_element compares one element at
  // a time and was 5 % of an export's bounds build.
  constexpr std::size_t kLanes = 8;
  std::array<float, kLanes> lo, hi;
  lo.fill(heights_.front());
  hi.fill(heights_.front());
  const std::size_t n = heights_.size(), body = n - n % kLanes;
  for (std::size_t i = 0; i < body; i += kLanes) {
    for (std::size_t k = 0; k < kLanes; ++k) {
      lo[k] = std::min(lo[k], heights_[i + k]);
      hi[k] = std::max(hi[k], heights_[i + k]);
    }
  }
  for (std::size_t i = body; i < n; ++i) {
    lo[0] = std::min(lo[0], heights_[i]);
    hi[0] = std::max(hi[0], heights_[i]);
  }
  minHeight_ = *std::min_element(lo.begin(), lo.end());
  maxHeight_ = *std::max_element(hi.begin(), hi.end());
}

void Terrain::commitEdit(const VertexBox& changed) {
  if (changed.empty()) return;
  // On a chart that glues its sides beyond a u seam an edit's box stands for its images too.
  std::vector<CutBox> regions;
  for (const VertexBox& r : gluedImages(*chart_, changed)) regions.push_back({r, {}});
  commitEdit(regions);
}

void Terrain::commitEdit(std::span<const CutBox> changed) {
  std::vector<VertexBox> regions;
  for (const CutBox& r : changed)
    if (!r.box.empty() && !r.cut.holdsNothing()) regions.push_back(r.box);
  if (regions.empty()) return;
  bounds_.update(*chart_, heights_, changed);
  // The global range only widens cheaply; a full scan is O(N^2) and the range is only used as
  // a conservative occluder, so track it incrementally over the changed region.
  for (const CutBox& c : changed) {
    // (Named, not bound: clang 14 cannot capture structured bindings.)
    const VertexBox& r = c.box;
    const Diagonals& cut = c.cut;
    if (r.empty()) continue;
    // (A cut's columns are in the grid: none on a chart with a u seam, whose columns wrap.)
    const bool useCut = !chart_->wrapsU();
    r.forEachColumnRange(grid(), [&](int uA, int uB) {
      for (int v = r.vBegin; v <= r.vEnd; ++v) {
        const int uFirst = useCut ? std::max(uA, cut.firstColumn(v)) : uA;
        const int uLast = useCut ? std::min(uB, cut.lastColumn(v)) : uB;
        for (int u = uFirst; u <= uLast; ++u) {
          const float x = heights_[grid().index(u, v)];
          minHeight_ = std::min(minHeight_, x);
          maxHeight_ = std::max(maxHeight_, x);
        }
      }
    });
  }
  revision_ = nextRevision();
  for (const VertexBox& r : regions) recordChange(r);
}

void Terrain::rebuildBounds(ErrorRule rule, BoundsContent content) {
  bounds_.build(*chart_, heights_, rule, content);
  refreshHeightRange();
  revision_ = nextRevision();
  // Called after heights changed wholesale as often as for a new rule: all may have changed.
  recordChange(VertexBox::all(grid()));
}

void Terrain::recordChange(const VertexBox& region) {
  changes_.push_back({revision_, region});
  if (changes_.size() > kKeptChanges) {
    oldestKnown_ = changes_.front().revision;
    changes_.pop_front();
  }
}

bool Terrain::changedSince(std::uint64_t revision, std::vector<VertexBox>& regions) const {
  regions.clear();
  if (revision < oldestKnown_ || revision > revision_) return false;
  // Revisions are unique across terrains: one this terrain never had is another's.
  if (revision != oldestKnown_ &&
      std::none_of(changes_.begin(), changes_.end(),
                   [&](const Change& c) { return c.revision == revision; }))
    return false;
  for (const Change& c : changes_)
    if (c.revision > revision) regions.push_back(c.region);
  return true;
}

}  // namespace ps::terrain
