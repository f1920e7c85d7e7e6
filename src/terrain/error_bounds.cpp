#include "terrain/error_bounds.hpp"

#include <algorithm>
#include <cmath>

#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
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

// A nested radius must exceed its child's by a margin, so that the view-dependent test, which
// is evaluated in floating point, stays monotone from child to parent even when a child's ball
// touches its parent's from inside.
constexpr double kRadiusMargin = 1.0 + 1e-7;

template <class ChartT>
struct Sampler {
  const ChartT& chart;
  const float* h;
  core::GridSize g;
  Eigen::Vector3d pos(GridPoint p) const {
    return chart.position(p.u, p.v, double(h[g.index(p.u, p.v)]));
  }
};

// Largest |P(q) - L_T(q)| over grid points q of triangle (a, b0, b1) (right angle at a).
template <class ChartT>
double exactTriangleDeviation(const Sampler<ChartT>& s, GridPoint a, GridPoint b0, GridPoint b1) {
  const Eigen::Vector3d pa = s.pos(a), d0 = s.pos(b0) - pa, d1 = s.pos(b1) - pa;
  double worst2 = 0.0;
  forEachGridPointInTriangle(a, b0, b1, [&](int u, int v, double w0, double w1) {
    const Eigen::Vector3d lin = pa + w0 * d0 + w1 * d1;
    worst2 = std::max(worst2, (s.pos({u, v}) - lin).squaredNorm());
  });
  return std::sqrt(worst2);
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
  BoundCodes* codes = codes_.data();

  auto computeVertex = [&](GridPoint p) {
    const Diamond d = Diamond::of(p);
    const Eigen::Vector3d P = sampler.pos(p);
    double childEps = 0.0, radius = 0.0;
    for (GridPoint c : {d.base0, d.base1, d.apex0, d.apex1}) {
      if (inGrid(g, c)) radius = std::max(radius, (sampler.pos(c) - P).norm());
    }
    for (int i = 0; i < d.childCount; ++i) {
      const GridPoint c = d.children[std::size_t(i)];
      if (!inGrid(g, c)) continue;
      const std::size_t ci = g.index(c.u, c.v);
      childEps = std::max(childEps, double(BoundCode::decode(codes[ci].error)));
      radius = std::max(
          radius, (double(BoundCode::decode(codes[ci].radius)) + (sampler.pos(c) - P).norm()) *
                      kRadiusMargin);
    }
    double e;
    // At level 0 a diamond's triangles hold no grid vertex but their corners and v itself, so
    // the exact deviation is the midpoint error: the wedgie formula below (half of all vertices
    // take this path, so skipping the triangle scans matters).
    if (rule == ErrorRule::kHybridExact && s <= kExactMaxHalfSize && level > 0) {
      e = childEps;
      if (inGrid(g, d.apex0))
        e = std::max(e, exactTriangleDeviation(sampler, d.apex0, d.base0, d.base1));
      if (inGrid(g, d.apex1))
        e = std::max(e, exactTriangleDeviation(sampler, d.apex1, d.base1, d.base0));
    } else {
      const Eigen::Vector3d mid = 0.5 * (sampler.pos(d.base0) + sampler.pos(d.base1));
      e = childEps + (P - mid).norm();
    }
    const std::size_t i = g.index(p.u, p.v);
    codes[i] = {BoundCode::encodeUp(e), BoundCode::encodeUp(radius)};
  };

  // Rows of this level inside the region.
  const int vFirst = ((region.vBegin + s - 1) / s) * s;
  std::vector<int> rows;
  for (int v = vFirst; v <= region.vEnd; v += s) {
    const bool vOdd = ((v / s) & 1) != 0;
    if (centre && !vOdd) continue;  // centre vertices sit on odd rows only
    rows.push_back(v);
  }
  std::size_t count = 0;
  region.forEachColumnRange(g, [&](int uA, int uB) {
    // Small regions (a typical edit near the fine levels) stay on this thread: waking the team
    // costs more than the work, and much more when the machine is busy.
    const bool parallel = double(rows.size()) * double(uB - uA + 1) / double(2 * s) > 20000.0;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : count) if (parallel)
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const int v = rows[r];
      const bool vOdd = ((v / s) & 1) != 0;
      // Columns: on an odd row, edge vertices have u/s even and centres u/s odd; on an even row
      // only edge vertices, u/s odd.
      const bool wantUOdd = centre || !vOdd;
      int u = ((uA + s - 1) / s) * s;
      if ((((u / s) & 1) != 0) != wantUOdd) u += s;
      for (; u <= uB; u += 2 * s) {
        if ((u == 0 || u == m) && (v == 0 || v == m)) continue;  // grid corners split nothing
        computeVertex({u, v});
        ++count;
      }
    }
  });
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
        computeVertex({0, v});
        computeVertex({m, v});
        const BoundCodes both{std::max(codes[a].error, codes[b].error),
                              std::max(codes[a].radius, codes[b].radius)};
        codes[a] = codes[b] = both;
      }
    }
  }
}

namespace {
template <class F>
void dispatchChart(const core::Chart& chart, F&& f) {
  if (auto* ll = dynamic_cast<const core::LatLongChart*>(&chart)) return f(*ll);
  f(chart);
}
}  // namespace

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

void ErrorBounds::build(const core::Chart& chart, std::span<const float> heights, ErrorRule rule) {
  const core::GridSize g = chart.grid();
  if (heights.size() != g.count()) {
    throw core::InputError("heights hold " + std::to_string(heights.size()) + " values, the " +
                           g.label() + " grid needs " + std::to_string(g.count()));
  }
  rule_ = rule;
  codes_.assign(g.count(), BoundCodes{});
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
