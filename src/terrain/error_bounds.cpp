#include "terrain/error_bounds.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/named_values.hpp"
#include "core/octahedral_chart.hpp"
#include "terrain/bound_kernels.hpp"
#include "terrain/diamond.hpp"
#include "terrain/level_plan.hpp"
#include "terrain/vertex_bounds.hpp"

namespace ps::terrain {

constexpr core::NameTable<ErrorRule, 3> kErrorRules{"error rule",
                                                    {{{ErrorRule::kWedgie, "wedgie"},
                                                      {ErrorRule::kHybridExact, "hybrid-exact"},
                                                      {ErrorRule::kHybridExact, "hybrid"}}}};

std::string toString(ErrorRule rule) {
  return kErrorRules.nameOf(rule);
}

ErrorRule errorRuleFromString(const std::string& s) {
  return kErrorRules.parse(s);
}

namespace {

// Copies a vertex's height and codes into the lattice, on the levels it holds (half-size
// >= 2^kLatticeShift).
struct LatticeCopy {
  const ErrorBounds* bounds = nullptr;  // null: this level is not on the lattice
  LatticeEntry* entries = nullptr;
  std::span<const float> heights;
  const BoundCodes* codes = nullptr;
  const core::GridSize g;
  bool active() const { return bounds != nullptr; }
  // childError: the largest error code among (u, v)'s children in the grid.
  void operator()(int u, int v, std::uint16_t childError) const {
    const std::size_t i = g.index(u, v);
    entries[bounds->latticeIndex(u, v)] = {heights[i], codes[i], childError};
  }
};

// One level's vertices within a region: the work items of the plan (bands of rows, the row
// kernels for their inner vertices, the scalar path for the rest), then the seam twins.
template <class ChartT>
class LevelPass {
 public:
  LevelPass(const ChartT& chart, const detail::LevelPlan& plan,
            const detail::VertexBounds<ChartT>& vertices,
            const detail::BoundKernels<ChartT>& kernels, BoundCodes* codes, int level,
            const LatticeCopy& lattice)
      : plan_(plan),
        vertices_(vertices),
        kernels_(kernels),
        codes_(codes),
        level_(level),
        lattice_(lattice),
        // On a wrapping chart the seam twins are computed after the rows, both halves and then
        // combined (seamTwins), whatever the rows would store for them: the rows leave them out
        // (on an edit across the seam they were computed twice, with the scalar path's scans
        // at levels 2-5).
        seamTwinsLater_(chart.wrapsU() && !plan.centre) {}

  // Work item `item` of the plan (rows of one band in one column range). Returns the vertices
  // computed.
  std::size_t item(std::size_t item) const { return band(item); }

  // Seam twins hold the combined values of both halves of their diamond. Returns the vertices
  // computed (none when the region does not reach the seam).
  std::size_t seamTwins(const core::GridSize& g, const VertexBox& region) const {
    if (!seamTwinsLater_) return 0;
    const int m = plan_.m, s = plan_.s;
    bool touchesSeam = region.coversAllColumns(g);
    region.forEachColumnRange(g, [&](int uA, int uB) { touchesSeam |= (uA == 0 || uB == m); });
    if (!touchesSeam) return 0;
    std::size_t count = 0;
    for (int v : plan_.rows) {
      if ((((v / s) & 1) == 0) || v == 0 || v == m)
        continue;  // seam vertices: u = 0 is even, so v/s odd
      const std::size_t a = g.index(0, v), b = g.index(m, v);
      // Recompute both halves in case the region only reached one of them.
      const std::uint16_t childError0 = vertices_.vertex({0, v});
      const std::uint16_t childErrorM = vertices_.vertex({m, v});
      count += 2;
      const BoundCodes both{std::max(codes_[a].error, codes_[b].error),
                            std::max(codes_[a].radius, codes_[b].radius)};
      codes_[a] = codes_[b] = both;
      if (lattice_.active()) {
        lattice_(0, v, childError0);
        lattice_(m, v, childErrorM);
      }
    }
    return count;
  }

 private:
  // The first and last vertex of a kernel row, strictly between the seam columns ({1, 0}: none).
  using Span = std::pair<int, int>;

  // One work item: a band of rows within one column range. Returns the vertices it computed.
  std::size_t band(std::size_t item) const {
    std::size_t count = 0;
    const std::size_t rowBegin = plan_.rowBegin(item), rowEnd = plan_.rowEnd(item);
    const std::pair<int, int> range = plan_.range(item);
    std::array<Span, detail::LevelPlan::kBand> spans{};
    std::size_t longest = 0;
    if (plan_.kernelLevel) kernels_.forgetRows();
    for (std::size_t r = rowBegin; r < rowEnd; ++r) {
      const int v = plan_.rows[r];
      const auto [uA, uB] = plan_.clip(v, range);
      if (uA > uB) {
        spans[r - rowBegin] = {1, 0};
        continue;
      }
      const int u = plan_.firstColumn(v, uA);
      if (plan_.kernelLevel && v >= plan_.s && v <= plan_.m - plan_.s) {
        spans[r - rowBegin] = kernelSpan(v, u, uB, count);
        const auto [first, last] = spans[r - rowBegin];
        if (first <= last)
          longest = std::max(longest, std::size_t((last - first) / (2 * plan_.s) + 1));
      } else {
        spans[r - rowBegin] = {1, 0};
        count += scalarRow(v, u, uB);
      }
    }
    return count + kernelRows(rowBegin, rowEnd, spans, longest);
  }

  // The row kernels take the vertices whose diamonds lie inside the grid; the seam columns
  // (u = 0 and u = m) take the scalar path here (on a wrapping chart in seamTwins). Returns
  // the kernels' span of the row from its first column u; adds the seam vertices to `count`.
  Span kernelSpan(int v, int u, int uB, std::size_t& count) const {
    const int step = 2 * plan_.s, m = plan_.m;
    const int first = u == 0 ? step : u;
    int last = u > uB ? u - step : u + ((uB - u) / step) * step;
    const bool lastIsSeam = last == m;
    if (lastIsSeam) last -= step;
    for (int seam : {0, m}) {
      if (!seamTwinsLater_ && u <= uB && ((seam == 0 && u == 0) || (seam == m && lastIsSeam))) {
        vertices_.compute({seam, v});
        ++count;
      }
    }
    return {first, last};
  }

  // Every vertex of row v from column u to uB on the scalar path (and onto the lattice).
  std::size_t scalarRow(int v, int u, int uB) const {
    const int m = plan_.m;
    std::size_t count = 0;
    for (; u <= uB; u += 2 * plan_.s) {
      if ((u == 0 || u == m) && (v == 0 || v == m)) continue;  // grid corners split nothing
      if (seamTwinsLater_ && (u == 0 || u == m)) continue;
      const std::uint16_t childError = vertices_.compute({u, v});
      if (lattice_.active()) lattice_(u, v, childError);
      ++count;
    }
    return count;
  }

  // The kernel spans of a band, in chunks whose rows of positions stay in the L1/L2 caches (a
  // whole row of level 5's nine rows was 1.8 MB and every stencil loop streamed it from L3).
  std::size_t kernelRows(std::size_t rowBegin, std::size_t rowEnd,
                         const std::array<Span, detail::LevelPlan::kBand>& spans,
                         std::size_t longest) const {
    constexpr int kChunk = 64;
    const int step = 2 * plan_.s;
    std::size_t count = 0;
    for (std::size_t chunk = 0; chunk * kChunk < longest; ++chunk) {
      for (std::size_t r = rowBegin; r < rowEnd; ++r) {
        const auto [first, last] = spans[r - rowBegin];
        const int chunkFirst = first + int(chunk) * kChunk * step;
        if (chunkFirst > last) continue;
        const int chunkLast = std::min(last, chunkFirst + (kChunk - 1) * step);
        const std::size_t n = std::size_t((chunkLast - chunkFirst) / step + 1);
        if (level_ <= 1)
          kernels_.fineRow(plan_.rows[r], chunkFirst, chunkLast);
        else
          kernels_.stencilRow(plan_.rows[r], chunkFirst, n);
        count += n;
      }
    }
    return count;
  }

  const detail::LevelPlan& plan_;
  const detail::VertexBounds<ChartT>& vertices_;
  const detail::BoundKernels<ChartT>& kernels_;
  BoundCodes* const codes_;
  const int level_;
  const LatticeCopy lattice_;
  const bool seamTwinsLater_;
};

}  // namespace

// On a chart that glues its sides beyond a u seam (core::Chart::gluesSidesBeyondSeam: the
// octahedral chart's mirrored sides, the torus's seam between v = 0 and v = m), a side vertex's
// diamond has one half in the grid at each twin. For the side vertices of this level within
// `regions`, on the sides glued so (a u seam's are seamTwins'), both halves are computed afresh
// (a twin may lie outside the regions) and both twins keep the larger codes; the next level's
// vertices then read the combined codes. Returns the vertices computed.
template <class ChartT>
std::size_t gluedTwins(const ChartT& chart, const detail::VertexBounds<ChartT>& vertices,
                       BoundCodes* codes, const LatticeCopy& lattice, int s,
                       const std::vector<CutBox>& regions) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const core::Gluing gl = chart.gluing();
  const bool vSides =
      gl.vSides == core::SideGluing::kMirror || gl.vSides == core::SideGluing::kSeam;
  const bool uSides = gl.uSides == core::SideGluing::kMirror;
  // The level's side vertices (k / s odd along the side) that a region reaches, each point once
  // (by its canonical vertex).
  std::vector<std::pair<int, int>> points;  // (v, u) of the canonical vertex
  for (const CutBox& region : regions) {
    // (Named, not bound: clang 14 cannot capture structured bindings.)
    const VertexBox& r = region.box;
    const Diagonals& cut = region.cut;
    // The side's vertices from a to b within the region's cut: along a row v = fixed its
    // columns, along a column u = fixed the rows where u + v and u - v are within the limits.
    auto add = [&](bool alongU, int fixed, int a, int b) {
      if (alongU) {
        a = std::max(a, cut.firstColumn(fixed)), b = std::min(b, cut.lastColumn(fixed));
      } else {
        a = std::max({a, cut.sumMin - fixed, fixed - cut.diffMax});
        b = std::min({b, cut.sumMax - fixed, fixed - cut.diffMin});
      }
      a = std::max(0, a), b = std::min(m, b);
      for (int k = ((a / s) | 1) * s; k <= b; k += 2 * s) {
        if (k <= 0 || k >= m) continue;
        const GridPoint c = alongU ? chart.canonical(k, fixed) : chart.canonical(fixed, k);
        points.emplace_back(c.v, c.u);
      }
    };
    if (vSides) {
      r.forEachColumnRange(g, [&](int uA, int uB) {
        if (r.vBegin <= 0) add(true, 0, uA, uB);
        if (r.vEnd >= m) add(true, m, uA, uB);
      });
    }
    if (uSides) {
      if (r.uBegin <= 0) add(false, 0, r.vBegin, r.vEnd);
      if (r.uEnd >= m) add(false, m, r.vBegin, r.vEnd);
    }
  }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  std::size_t count = 0;
  for (const auto& [v, u] : points) {
    GridPoint twins[4];
    const int n = chart.twins(u, v, twins);
    BoundCodes both{};
    std::uint16_t childError[4];
    for (int t = 0; t < n; ++t) {
      childError[t] = vertices.compute(twins[t]);
      const BoundCodes& c = codes[g.index(twins[t].u, twins[t].v)];
      both = {std::max(both.error, c.error), std::max(both.radius, c.radius)};
    }
    // The lattice takes the combined codes (the tessellator reads a twin there from half-size
    // 8 up): copied before combining, a twin's entry held its own half's, the twins split
    // differently, and the mesh cracked along the fold (StressEdits at 8x its size found it).
    // Each keeps its own children's largest error: those are the children on its side.
    for (int t = 0; t < n; ++t) {
      codes[g.index(twins[t].u, twins[t].v)] = both;
      if (lattice.active()) lattice(twins[t].u, twins[t].v, childError[t]);
    }
    count += std::size_t(n);
  }
  return count;
}

namespace {

// Sorts regions and replaces those whose boxes overlap or touch by the box around both, cut by
// the hull of both cuts, until none overlap: one pass over their union instead of one per
// region (a corner's four images, grown over the upper levels).
void mergeBoxes(std::vector<CutBox>& regions) {
  std::sort(regions.begin(), regions.end(), [](const CutBox& x, const CutBox& y) {
    const VertexBox &a = x.box, &b = y.box;
    return std::tie(a.vBegin, a.uBegin, a.vEnd, a.uEnd) <
           std::tie(b.vBegin, b.uBegin, b.vEnd, b.uEnd);
  });
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < regions.size() && !merged; ++i)
      for (std::size_t j = i + 1; j < regions.size() && !merged; ++j) {
        const VertexBox &a = regions[i].box, &b = regions[j].box;
        if (a.uBegin > b.uEnd + 1 || b.uBegin > a.uEnd + 1 || a.vBegin > b.vEnd + 1 ||
            b.vBegin > a.vEnd + 1)
          continue;
        regions[i] = {{std::min(a.uBegin, b.uBegin), std::max(a.uEnd, b.uEnd),
                       std::min(a.vBegin, b.vBegin), std::max(a.vEnd, b.vEnd)},
                      regions[i].cut.hull(regions[j].cut)};
        regions.erase(regions.begin() + std::ptrdiff_t(j));
        merged = true;
      }
  }
}

// The positions the row kernels' levels read in an update of the `dirty` regions, computed
// once: each region grown as the levels grow it and by the rows and columns a vertex of theirs
// reads, with its images across glued sides (update() computes those), merged as update()
// merges them. A row the boxes do not hold (the kernels' regions merged beyond them) is
// computed as before. None for a larger edit (the buffer stays with the thread).
template <class ChartT>
detail::PositionBoxes positionBoxes(const ChartT& chart, std::span<const float> heights,
                                    const std::vector<CutBox>& dirty) {
  constexpr std::size_t kMaxVertices = std::size_t(1) << 22;  // 96 MB of positions
  const core::GridSize g = chart.grid();
  int reach = ErrorBounds::kExactMaxHalfSize + 1;
  for (int l = 0; levelHalfSize(l) <= ErrorBounds::kExactMaxHalfSize; ++l)
    reach += levelHalfSize(l);
  std::vector<CutBox> areas;
  for (const CutBox& r : dirty) {
    const CutBox grown{r.box.grown(reach, g, false), r.cut.grown(reach)};
    const std::vector<CutBox> images = gluedImages(chart, grown, false);
    areas.insert(areas.end(), images.begin(), images.end());
  }
  mergeBoxes(areas);
  std::size_t total = 0;
  std::vector<std::pair<std::size_t, int>> rows;  // (box, v)
  for (std::size_t b = 0; b < areas.size(); ++b) {
    const VertexBox& a = areas[b].box;
    total += std::size_t(a.uEnd - a.uBegin + 1) * std::size_t(a.vEnd - a.vBegin + 1);
    for (int v = a.vBegin; v <= a.vEnd; ++v) rows.push_back({b, v});
  }
  if (total > kMaxVertices) return {};
  thread_local std::vector<double> storage;
  if (storage.size() < 3 * total) storage.resize(3 * total);
  double* const x = storage.data();  // this thread's (the team's threads have their own)
  detail::PositionBoxes out;
  std::vector<std::size_t> offset;
  std::size_t at = 0;
  for (const auto& [a, cut] : areas) {
    out.boxes.push_back({a, cut, x + at, x + total + at, x + 2 * total + at});
    offset.push_back(at);
    at += std::size_t(a.uEnd - a.uBegin + 1) * std::size_t(a.vEnd - a.vBegin + 1);
  }
  // Each row within its box's cut: the rest of the box is never read (PositionBoxes::row).
  auto fill = [&](std::size_t i) {
    const auto [b, v] = rows[i];
    const auto& [a, cut] = areas[b];
    const int uA = std::max(a.uBegin, cut.firstColumn(v)), uB = std::min(a.uEnd, cut.lastColumn(v));
    if (uA > uB) return;
    const std::size_t k = offset[b] +
                          std::size_t(v - a.vBegin) * std::size_t(a.uEnd - a.uBegin + 1) +
                          std::size_t(uA - a.uBegin);
    chart.rowPositions(v, uA, uB, heights.data() + g.index(0, v),
                       {x + k, x + total + k, x + 2 * total + k});
  };
  const std::size_t n = rows.size();
  if (total > 32768) {
#pragma omp parallel for schedule(dynamic, 8)
    for (std::size_t i = 0; i < n; ++i) fill(i);
  } else {
    for (std::size_t i = 0; i < n; ++i) fill(i);
  }
  return out;
}

}  // namespace

template <class ChartT>
void ErrorBounds::computeLevel(const ChartT& chart, std::span<const float> heights, int level,
                               std::span<const CutBox> regions,
                               const std::vector<CutBox>* gluedRegions,
                               const detail::PositionBoxes* boxes) {
  static_assert(kExactMaxHalfSize < (1 << kLatticeShift),
                "the row kernels' levels hold no lattice vertex: they do not copy to it");
  const core::GridSize g = chart.grid();
  std::vector<detail::LevelPlan> plans;
  plans.reserve(regions.size());
  for (const CutBox& r : regions) plans.emplace_back(g, level, r);
  BoundCodes* codes = codes_.data();
  const detail::VertexBounds<ChartT> vertices(chart, heights.data(), codes, level, rule_,
                                              hasRadii(), boxes);
  const detail::BoundKernels<ChartT> kernels(chart, heights.data(), codes, level, rule_, hasRadii(),
                                             boxes);
  const int s = levelHalfSize(level);
  const bool onLattice = !lattice_.empty() && s >= (1 << kLatticeShift);
  const LatticeCopy lattice{onLattice ? this : nullptr, lattice_.data(), heights, codes, g};
  std::vector<LevelPass<ChartT>> passes;
  passes.reserve(plans.size());
  // The regions' work items in one loop (first[k]: region k's first), on the team when their
  // work together pays for it: a corner of the octahedral chart is four images a level, and
  // one team for them waits once for its last item instead of four times.
  std::vector<std::size_t> first{0};
  double work = 0;
  for (const detail::LevelPlan& plan : plans) {
    passes.emplace_back(chart, plan, vertices, kernels, codes, level, lattice);
    first.push_back(first.back() + plan.items);
    work += plan.work;
  }
  const std::size_t items = first.back();
  auto run = [&](std::size_t i) {
    const std::size_t k =
        std::size_t(std::upper_bound(first.begin(), first.end(), i) - first.begin()) - 1;
    return passes[k].item(i - first[k]);
  };
  std::size_t count = 0;
  if (work > detail::LevelPlan::kParallelWork) {
#pragma omp parallel for schedule(dynamic, s <= kExactMaxHalfSize ? 1 : 4) reduction(+ : count)
    for (std::size_t i = 0; i < items; ++i) count += run(i);
  } else {
    // Not through the OpenMP runtime: a region with if (false) still sets up a team of one
    // and wakes the pool's sleeping threads (futex calls, about 2 us a level: a 150 km edit
    // at 2049^2, whose levels all stay on this thread, took 0.138 ms with it, 0.098 without).
    for (std::size_t i = 0; i < items; ++i) count += run(i);
  }
  for (std::size_t k = 0; k < plans.size(); ++k) count += passes[k].seamTwins(g, regions[k].box);
  lastUpdateCount_ += count;
  if (gluedRegions && !levelIsCentre(level))
    lastUpdateCount_ += gluedTwins(chart, vertices, codes, lattice, s, *gluedRegions);
}

namespace {
template <class F>
void dispatchChart(const core::Chart& chart, F&& f) {
  // The concrete charts are final with inline positions: dispatching once here lets the compiler
  // inline them into the per-vertex loops (a virtual call per sample otherwise).
  if (auto* ll = dynamic_cast<const core::LatLongChart*>(&chart)) return f(*ll);
  if (auto* flat = dynamic_cast<const core::FlatChart*>(&chart)) return f(*flat);
  if (auto* oct = dynamic_cast<const core::OctahedralChart*>(&chart)) return f(*oct);
  f(chart);
}
}  // namespace

ErrorBounds::LatticeLevel ErrorBounds::latticeLevel(int halfSize, bool centre) const {
  const int b = std::countr_zero(unsigned(halfSize));
  const std::size_t half = std::size_t(gridM_ >> (b + 1));
  return {lattice_.data() + latticeOffsets_[std::size_t(b)][centre ? 1 : 0],
          centre ? half : half + 1, centre ? b + 1 : b, b + 1};
}

std::size_t ErrorBounds::latticeIndex(int u, int v) const {
  // The level is the lowest set bit of u | v: a centre where both u/s and v/s are odd.
  const int b = std::countr_zero(unsigned(u | v));
  const bool centre = ((u >> b) & (v >> b) & 1) != 0;
  const LatticeLevel level = latticeLevel(1 << b, centre);
  return std::size_t(&level.at(u, v) - lattice_.data());
}

std::vector<std::uint16_t> ErrorBounds::errorCodes() const {
  std::vector<std::uint16_t> out(codes_.size());
  for (std::size_t i = 0; i < codes_.size(); ++i) out[i] = codes_[i].error;
  return out;
}

std::vector<std::uint16_t> ErrorBounds::radiusCodes() const {
  std::vector<std::uint16_t> out(codes_.size());
  for (std::size_t i = 0; i < codes_.size(); ++i) out[i] = codes_[i].radius;
  return out;
}

void ErrorBounds::build(const core::Chart& chart, std::span<const float> heights, ErrorRule rule,
                        BoundsContent content) {
  const core::GridSize g = chart.grid();
  if (heights.size() != g.count()) {
    throw core::InputError("heights hold " + std::to_string(heights.size()) + " values, the " +
                           g.label() + " grid needs " + std::to_string(g.count()));
  }
  rule_ = rule;
  content_ = content;
  codes_.assign(g.count(), BoundCodes{});
  if (hasRadii()) {
    // Level by level: centres of half-size s at (s (2i + 1), s (2j + 1)), m/2s by m/2s; edges at
    // (u, v) with u/s + v/s odd, m/s + 1 rows of m/2s + 1 (the even rows leave their last
    // entry unused).
    gridM_ = g.m();
    latticeOffsets_.assign(std::size_t(g.n()), {0, 0});
    std::size_t size = 0;
    for (int b = kLatticeShift; b < g.n(); ++b) {
      const std::size_t half = std::size_t(g.m() >> (b + 1));  // m / 2s
      latticeOffsets_[std::size_t(b)][0] = size;
      size += (2 * half + 1) * (half + 1);
      latticeOffsets_[std::size_t(b)][1] = size;
      size += half * half;
    }
    lattice_.assign(size, LatticeEntry{});
  } else {
    latticeOffsets_.clear();
    lattice_ = Lattice{};
  }
  lastUpdateCount_ = 0;
  const std::vector<CutBox> all{{VertexBox::all(g), {}}};
  const std::vector<CutBox>* glued = chart.gluesSidesBeyondSeam() ? &all : nullptr;
  dispatchChart(chart, [&](const auto& c) {
    for (int level = 0; level < levelCount(g); ++level) computeLevel(c, heights, level, all, glued);
  });
}

void ErrorBounds::update(const core::Chart& chart, std::span<const float> heights,
                         const VertexBox& dirty) {
  update(chart, heights, std::span<const VertexBox>(&dirty, 1));
}

void ErrorBounds::update(const core::Chart& chart, std::span<const float> heights,
                         std::span<const VertexBox> dirty) {
  std::vector<CutBox> regions;
  for (const VertexBox& r : dirty) regions.push_back({r, {}});
  update(chart, heights, regions);
}

void ErrorBounds::update(const core::Chart& chart, std::span<const float> heights,
                         std::span<const CutBox> dirty) {
  const core::GridSize g = chart.grid();
  lastUpdateCount_ = 0;
  std::vector<CutBox> regions;
  for (const CutBox& r : dirty) {
    if (r.box.empty() || r.cut.holdsNothing()) continue;
    regions.push_back(r);
    if (chart.wrapsU()) regions.back().cut = {};  // unwrapped columns: the cut would not fit
  }
  if (regions.empty()) return;
  const bool glued = chart.gluesSidesBeyondSeam();
  dispatchChart(chart, [&](const auto& c) {
    // The octahedral chart's positions once for all the levels (lat-long's and the
    // flat chart's are look-ups: as cheap as reading them back).
    detail::PositionBoxes boxes;
    if constexpr (std::is_same_v<std::decay_t<decltype(c)>, core::OctahedralChart>)
      boxes = positionBoxes(c, heights, regions);
    const detail::PositionBoxes* kernelBoxes = boxes.boxes.empty() ? nullptr : &boxes;
    std::vector<CutBox> level;
    for (int l = 0; l < levelCount(g); ++l) {
      // A vertex of this level reads heights and children within its half-size s.
      for (CutBox& r : regions) {
        r.box = r.box.grown(levelHalfSize(l), g, c.wrapsU());
        r.cut = r.cut.grown(levelHalfSize(l));
      }
      if (!glued) {
        // One region at a time: dirty regions may overlap (two passes may not write one vertex).
        for (const CutBox& r : regions)
          computeLevel(c, heights, l, std::span<const CutBox>(&r, 1), nullptr, kernelBoxes);
        continue;
      }
      // Where a region reaches a glued side, the grid beyond it changed too: the region's
      // images across the sides (core::Chart::gluedImages: the octahedral chart's mirrors, the
      // torus's v -> m - v) are computed as well, and the touched sides' twins combined once,
      // after all of them.
      level.clear();
      for (const CutBox& r : regions) {
        const std::vector<CutBox> images = gluedImages(c, r, false);
        level.insert(level.end(), images.begin(), images.end());
      }
      mergeBoxes(level);  // disjoint: their passes may run together
      computeLevel(c, heights, l, level, &level, kernelBoxes);
    }
  });
}

}  // namespace ps::terrain
