#include "terrain/error_bounds.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <type_traits>
#include <utility>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "terrain/bound_kernels.hpp"
#include "terrain/diamond.hpp"

namespace ps::terrain {

std::string toString(ErrorRule rule) {
  return rule == ErrorRule::kWedgie ? "wedgie" : "hybrid-exact";
}

ErrorRule errorRuleFromString(const std::string& s) {
  if (s == "wedgie") return ErrorRule::kWedgie;
  if (s == "hybrid-exact" || s == "hybrid") return ErrorRule::kHybridExact;
  throw core::InputError("unknown error rule '" + s + "' (expected wedgie or hybrid-exact)");
}

namespace {

using detail::kRadiusMargin;

template <class ChartT>
struct Sampler {
  const ChartT& chart;
  const float* h;
  core::GridSize g;
  Eigen::Vector3d pos(GridPoint p) const {
    return chart.position(p.u, p.v, double(h[g.index(p.u, p.v)]));
  }
};

// Largest |P(q) - L_T(q)| over the grid points q strictly inside triangle (a, b0, b1) (right
// angle at a), visited row span by row span, L_T from q's barycentric weights. The points on
// its edges are left to the callers: the legs are the hypotenuses of v's children, on which L_T
// is the children's own interpolant, so the children's exact bounds already cover them; the
// hypotenuse is shared with the diamond's other triangle (hypotenuseDeviation, once for both).
template <class ChartT>
double interiorDeviation(const Sampler<ChartT>& s, GridPoint a, GridPoint b0, GridPoint b1) {
  if constexpr (std::is_same_v<ChartT, core::FlatChart>) {
    // x and y are linear in (u, v) on a flat chart, so the deviation is the height's alone:
    // the same value without the rounding noise of the two planar components.
    const double ha = s.h[s.g.index(a.u, a.v)];
    const double d0 = s.h[s.g.index(b0.u, b0.v)] - ha, d1 = s.h[s.g.index(b1.u, b1.v)] - ha;
    double worst = 0.0;
    forEachGridPointInTriangle(
        a, b0, b1,
        [&](int u, int v, double w0, double w1) {
          worst =
              std::max(worst, std::abs(double(s.h[s.g.index(u, v)]) - (ha + w0 * d0 + w1 * d1)));
        },
        TriangleSet::kOpen);
    return worst;
  } else {
    const Eigen::Vector3d pa = s.pos(a), d0 = s.pos(b0) - pa, d1 = s.pos(b1) - pa;
    double worst2 = 0.0;
    forEachGridPointInTriangle(
        a, b0, b1,
        [&](int u, int v, double w0, double w1) {
          worst2 = std::max(worst2, (s.pos({u, v}) - (pa + w0 * d0 + w1 * d1)).squaredNorm());
        },
        TriangleSet::kOpen);
    return std::sqrt(worst2);
  }
}

// Largest deviation of the grid points strictly between b0 and b1 (v among them) from the
// segment b0-b1, which is where both of the diamond's triangles put them.
template <class ChartT>
double hypotenuseDeviation(const Sampler<ChartT>& s, GridPoint b0, GridPoint b1) {
  const int steps = std::max(std::abs(b1.u - b0.u), std::abs(b1.v - b0.v));
  const int du = (b1.u - b0.u) / steps, dv = (b1.v - b0.v) / steps;
  const double inv = 1.0 / steps;
  if constexpr (std::is_same_v<ChartT, core::FlatChart>) {
    const double h0 = s.h[s.g.index(b0.u, b0.v)], dh = s.h[s.g.index(b1.u, b1.v)] - h0;
    double worst = 0.0;
    for (int k = 1; k < steps; ++k) {
      const double hq = s.h[s.g.index(b0.u + k * du, b0.v + k * dv)];
      worst = std::max(worst, std::abs(hq - (h0 + double(k) * inv * dh)));
    }
    return worst;
  } else {
    const Eigen::Vector3d p0 = s.pos(b0), d = s.pos(b1) - p0;
    double worst2 = 0.0;
    for (int k = 1; k < steps; ++k) {
      const Eigen::Vector3d q = s.pos({b0.u + k * du, b0.v + k * dv});
      worst2 = std::max(worst2, (q - (p0 + double(k) * inv * d)).squaredNorm());
    }
    return std::sqrt(worst2);
  }
}

}  // namespace

template <class ChartT>
void ErrorBounds::computeLevel(const ChartT& chart, std::span<const float> heights, int level,
                               const GridRegion& region) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const int s = levelHalfSize(level);
  const bool centre = levelIsCentre(level);
  const Sampler<ChartT> sampler{chart, heights.data(), g};
  const ErrorRule rule = rule_;
  const bool withRadii = hasRadii();
  BoundCodes* codes = codes_.data();
  const bool levelOnLattice = !lattice_.empty() && s >= (1 << kLatticeShift);
  // childError: the largest error code among (u, v)'s children in the grid (computeVertex's).
  auto copyToLattice = [&](int u, int v, std::uint16_t childError) {
    const std::size_t i = g.index(u, v);
    lattice_[latticeIndex(u, v)] = {heights[i], codes[i], childError};
  };

  // Returns the largest error code among p's children in the grid.
  auto computeVertex = [&](GridPoint p) -> std::uint16_t {
    const Diamond d = Diamond::of(p);
    const Eigen::Vector3d P = sampler.pos(p);
    // Codes are monotone: the largest child code is the largest child bound, one table lookup
    // instead of four (the 256 KB table does not fit the L1 cache).
    std::uint16_t childCode = 0;
    double radius = 0.0;
    int childrenInGrid = 0;
    for (int i = 0; i < d.childCount; ++i) {
      const GridPoint c = d.children[std::size_t(i)];
      if (!inGrid(g, c)) continue;
      ++childrenInGrid;
      const std::size_t ci = g.index(c.u, c.v);
      childCode = std::max(childCode, codes[ci].error);
      if (withRadii) {
        radius = std::max(
            radius, (double(BoundCode::decode(codes[ci].radius)) + (sampler.pos(c) - P).norm()) *
                        kRadiusMargin);
      }
    }
    // Every corner of the diamond is a corner of one of the four children's diamonds, which
    // their radii cover: |P(corner) - P| <= radius(child) + |P(child) - P|, and the margin puts
    // that term far above the rounding of the direct distance. So the corners only matter where
    // a child falls outside the grid.
    if (withRadii && childrenInGrid < 4) {
      double corner2 = 0.0;
      for (GridPoint c : {d.base0, d.base1, d.apex0, d.apex1}) {
        if (inGrid(g, c)) corner2 = std::max(corner2, (sampler.pos(c) - P).squaredNorm());
      }
      radius = std::max(radius, std::sqrt(corner2));
    }
    const double childEps = BoundCode::decode(childCode);
    double e;
    // At level 0 a diamond's triangles hold no grid vertex but their corners and v itself, so
    // the exact deviation is the midpoint error: the wedgie formula below (half of all vertices
    // take this path, so skipping the triangle scans matters).
    if (rule == ErrorRule::kHybridExact && level == 1) {
      // A level-1 diamond's triangles hold their corners (deviation 0), v on the hypotenuse
      // (the midpoint error) and the midpoints of their legs, which are v's four children:
      // their own midpoint errors, already bounded by childEps. So the exact maximum is this,
      // without scanning (a quarter of all vertices).
      const Eigen::Vector3d mid = 0.5 * (sampler.pos(d.base0) + sampler.pos(d.base1));
      e = std::max(childEps, (P - mid).norm());
    } else if (rule == ErrorRule::kHybridExact && s <= kExactMaxHalfSize && level > 0) {
      // The triangles' grid points: corners (deviation 0), legs (the children's hypotenuses,
      // covered by childEps), the shared hypotenuse and the two interiors.
      e = std::max(childEps, hypotenuseDeviation(sampler, d.base0, d.base1));
      if (inGrid(g, d.apex0))
        e = std::max(e, interiorDeviation(sampler, d.apex0, d.base0, d.base1));
      if (inGrid(g, d.apex1))
        e = std::max(e, interiorDeviation(sampler, d.apex1, d.base1, d.base0));
    } else {
      const Eigen::Vector3d mid = 0.5 * (sampler.pos(d.base0) + sampler.pos(d.base1));
      e = childEps + (P - mid).norm();
    }
    // A bound the children already give keeps their code: encodeUp(decode(c)) == c, so this
    // is the same code without the encoding's lookups.
    const std::uint16_t errorCode = e == childEps ? childCode : BoundCode::encodeUp(e);
    const std::size_t i = g.index(p.u, p.v);
    codes[i] = {errorCode, withRadii ? BoundCode::encodeUp(radius) : std::uint16_t(0)};
    return childCode;
  };

  // Level 0 is half of all vertices: edge vertices of half-size 1, no children, no grid vertex
  // inside their triangles but their corners. The same values as computeVertex, without the
  // general diamond (7.8 -> 4.4 ms of a 513² build).
  auto computeLeaf = [&](GridPoint p) {
    const bool horizontal = (p.u & 1) != 0;
    const GridPoint b0 = horizontal ? GridPoint{p.u - 1, p.v} : GridPoint{p.u, p.v - 1};
    const GridPoint b1 = horizontal ? GridPoint{p.u + 1, p.v} : GridPoint{p.u, p.v + 1};
    const Eigen::Vector3d P = sampler.pos(p);
    const Eigen::Vector3d B0 = sampler.pos(b0), B1 = sampler.pos(b1);
    double radius = 0.0;
    if (withRadii) {
      // sqrt is monotone and correctly rounded: one sqrt of the largest square is the largest
      // of the four distances, bit for bit.
      double r2 = std::max((B0 - P).squaredNorm(), (B1 - P).squaredNorm());
      const GridPoint a0 = horizontal ? GridPoint{p.u, p.v - 1} : GridPoint{p.u - 1, p.v};
      const GridPoint a1 = horizontal ? GridPoint{p.u, p.v + 1} : GridPoint{p.u + 1, p.v};
      if (inGrid(g, a0)) r2 = std::max(r2, (sampler.pos(a0) - P).squaredNorm());
      if (inGrid(g, a1)) r2 = std::max(r2, (sampler.pos(a1) - P).squaredNorm());
      radius = std::sqrt(r2);
    }
    const Eigen::Vector3d mid = 0.5 * (B0 + B1);
    const double e = (P - mid).norm();
    codes[g.index(p.u, p.v)] = {BoundCode::encodeUp(e),
                                withRadii ? BoundCode::encodeUp(radius) : std::uint16_t(0)};
  };

  const detail::BoundKernels<ChartT> kernels(chart, heights.data(), codes, level, rule, withRadii);

  // Rows of this level inside the region.
  const int vFirst = ((region.vBegin + s - 1) / s) * s;
  std::vector<int> rows;
  for (int v = vFirst; v <= region.vEnd; v += s) {
    const bool vOdd = ((v / s) & 1) != 0;
    if (centre && !vOdd) continue;  // centre vertices sit on odd rows only
    rows.push_back(v);
  }
  // A region across the seam is two column ranges; one loop over (row, range) items keeps both
  // cores on one team instead of two fork-joins per level, each with half the work.
  std::array<std::pair<int, int>, 2> ranges;
  std::size_t rangeCount = 0;
  double work = 0;
  region.forEachColumnRange(g, [&](int uA, int uB) {
    ranges[rangeCount++] = {uA, uB};
    work += double(rows.size()) * double(uB - uA + 1) / double(2 * s);
  });
  // Small regions (a typical edit near the fine levels) stay on this thread: waking the team
  // costs more than the work, and much more when the machine is busy. About 2,000 vertices
  // (0.1-0.2 ms of work) pays: at 20,000 the pole's level 6 (17,000 vertices, 1.7 ms) and most
  // levels of a 600 km edit elsewhere ran on one thread (bench deform: 300 km polar cap
  // 19.5-21.5 -> 17.5-20.2 ms, latitude 30 / 600 km 6.6-7.7 -> 5.2-6.0 ms).
  const bool parallel = work > 2000.0;
  // Levels 0-5 go to the row kernels in bands of kBand rows, chunk by chunk across the band, so
  // that neighbouring rows share the rows of positions they read (BoundKernels::forgetRows at
  // the start of an item: nothing is shared across items, whose order is the scheduler's).
  const bool kernelLevel = s <= kExactMaxHalfSize;
  static_assert(kExactMaxHalfSize < (1 << kLatticeShift),
                "the row kernels' levels hold no lattice vertex: they do not copy to it");
  constexpr std::size_t kBand = 8;
  const std::size_t band = kernelLevel ? kBand : 1;
  const std::size_t bandCount = (rows.size() + band - 1) / band;
  // The first column of the level on row v at or after uA.
  auto firstColumn = [&](int v, int uA) {
    // On an odd row (v/s odd), edge vertices have u/s even and centres u/s odd; on an even row
    // only edge vertices, u/s odd.
    const bool wantUOdd = centre || ((v / s) & 1) == 0;
    int u = ((uA + s - 1) / s) * s;
    if ((((u / s) & 1) != 0) != wantUOdd) u += s;
    return u;
  };
  // On a wrapping chart the seam twins are computed after the rows, both halves and then
  // combined (below), whatever this loop stores for them: it leaves them out (on an edit across
  // the seam they were computed twice, with the scalar path's scans at levels 2-5).
  const bool seamTwinsLater = chart.wrapsU() && !centre;
  // One work item: a band of rows within one column range. Returns the vertices it computed.
  auto computeItem = [&](std::size_t item) {
    std::size_t count = 0;
    const std::size_t rowBegin = (item / rangeCount) * band;
    const std::size_t rowEnd = std::min(rows.size(), rowBegin + band);
    const auto [uA, uB] = ranges[item % rangeCount];
    const int step = 2 * s;
    // Kernel rows: their vertices strictly between the seam columns, first .. last.
    std::array<std::pair<int, int>, kBand> spans{};
    std::size_t longest = 0;
    if (kernelLevel) kernels.forgetRows();
    for (std::size_t r = rowBegin; r < rowEnd; ++r) {
      const int v = rows[r];
      int u = firstColumn(v, uA);
      if (kernelLevel && v >= s && v <= m - s) {
        // The row kernels take the vertices whose diamonds lie inside the grid; the seam
        // columns (u = 0 and u = m) take the general path (on a wrapping chart in the twin
        // pass below).
        const int first = u == 0 ? step : u;
        int last = u > uB ? u - step : u + ((uB - u) / step) * step;
        const bool lastIsSeam = last == m;
        if (lastIsSeam) last -= step;
        spans[r - rowBegin] = {first, last};
        if (first <= last) longest = std::max(longest, std::size_t((last - first) / step + 1));
        for (int seam : {0, m}) {
          if (!seamTwinsLater && u <= uB && ((seam == 0 && u == 0) || (seam == m && lastIsSeam))) {
            if (level == 0)
              computeLeaf({seam, v});
            else
              computeVertex({seam, v});
            ++count;
          }
        }
        continue;
      }
      spans[r - rowBegin] = {1, 0};  // none
      for (; u <= uB; u += step) {
        if ((u == 0 || u == m) && (v == 0 || v == m)) continue;  // grid corners split nothing
        if (seamTwinsLater && (u == 0 || u == m)) continue;
        if (level == 0) {
          computeLeaf({u, v});
        } else {
          const std::uint16_t childError = computeVertex({u, v});
          if (levelOnLattice) copyToLattice(u, v, childError);
        }
        ++count;
      }
    }
    // In chunks whose rows of positions stay in the L1/L2 caches (a whole row of level 5's
    // nine rows was 1.8 MB and every stencil loop streamed it from L3).
    constexpr int kChunk = 64;
    for (std::size_t chunk = 0; chunk * kChunk < longest; ++chunk) {
      for (std::size_t r = rowBegin; r < rowEnd; ++r) {
        const auto [first, last] = spans[r - rowBegin];
        const int chunkFirst = first + int(chunk) * kChunk * step;
        if (chunkFirst > last) continue;
        const int chunkLast = std::min(last, chunkFirst + (kChunk - 1) * step);
        const std::size_t n = std::size_t((chunkLast - chunkFirst) / step + 1);
        if (level <= 1)
          kernels.fineRow(rows[r], chunkFirst, chunkLast);
        else
          kernels.stencilRow(rows[r], chunkFirst, n);
        count += n;
      }
    }
    return count;
  };
  const std::size_t items = bandCount * rangeCount;
  std::size_t count = 0;
  if (parallel) {
#pragma omp parallel for schedule(dynamic, kernelLevel ? 1 : 4) reduction(+ : count)
    for (std::size_t item = 0; item < items; ++item) count += computeItem(item);
  } else {
    // Not through the OpenMP runtime: a region with if (false) still sets up a team of one
    // and wakes the pool's sleeping threads (futex calls, about 2 us a level: a 150 km edit at
    // 2049^2, whose levels all stay on this thread, took 0.138 ms with it, 0.098 without).
    for (std::size_t item = 0; item < items; ++item) count += computeItem(item);
  }
  lastUpdateCount_ += count;

  // Seam twins hold the combined values of both halves of their diamond.
  if (chart.wrapsU() && !centre) {
    bool touchesSeam = region.coversAllColumns(g);
    region.forEachColumnRange(g, [&](int uA, int uB) { touchesSeam |= (uA == 0 || uB == m); });
    if (touchesSeam) {
      for (int v : rows) {
        if ((((v / s) & 1) == 0) || v == 0 || v == m)
          continue;  // seam vertices: u = 0 is even, so v/s odd
        const std::size_t a = g.index(0, v), b = g.index(m, v);
        // Recompute both halves in case the region only reached one of them.
        const std::uint16_t childError0 = computeVertex({0, v});
        const std::uint16_t childErrorM = computeVertex({m, v});
        lastUpdateCount_ += 2;
        const BoundCodes both{std::max(codes[a].error, codes[b].error),
                              std::max(codes[a].radius, codes[b].radius)};
        codes[a] = codes[b] = both;
        if (levelOnLattice) {
          copyToLattice(0, v, childError0);
          copyToLattice(m, v, childErrorM);
        }
      }
    }
  }
}

namespace {
template <class F>
void dispatchChart(const core::Chart& chart, F&& f) {
  // The concrete charts are final with inline positions: dispatching once here lets the compiler
  // inline them into the per-vertex loops (a virtual call per sample otherwise).
  if (auto* ll = dynamic_cast<const core::LatLongChart*>(&chart)) return f(*ll);
  if (auto* flat = dynamic_cast<const core::FlatChart*>(&chart)) return f(*flat);
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
  dispatchChart(chart, [&](const auto& c) {
    for (int level = 0; level < levelCount(g); ++level)
      computeLevel(c, heights, level, GridRegion::all(g));
  });
}

void ErrorBounds::update(const core::Chart& chart, std::span<const float> heights,
                         const GridRegion& dirty) {
  const core::GridSize g = chart.grid();
  lastUpdateCount_ = 0;
  if (dirty.empty()) return;
  dispatchChart(chart, [&](const auto& c) {
    GridRegion region = dirty;
    for (int level = 0; level < levelCount(g); ++level) {
      // A vertex of this level reads heights and children within its half-size s.
      region = region.grown(levelHalfSize(level), g, c.wrapsU());
      computeLevel(c, heights, level, region);
    }
  });
}

}  // namespace ps::terrain
