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
  auto copyToLattice = [&](int u, int v) {
    const std::size_t i = g.index(u, v);
    lattice_[latticeIndex(u, v)] = {heights[i], codes[i]};
  };

  auto computeVertex = [&](GridPoint p) {
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

  // Levels 0 and 1 are three quarters of all vertices, and away from the grid's edges every one
  // of them has all four neighbours in the grid: row kernels over one row's positions, computed
  // once per row (a vertex's five positions were computed afresh for every vertex that reads
  // them), with the square roots of a row in one loop. Same formulas as computeLeaf and
  // computeVertex, so the same codes.
  struct RowStrip {
    std::vector<double> x, y, z;
  };
  auto fillStrip = [&](RowStrip& strip, int v, int uLo, int uHi) {
    const std::size_t n = std::size_t(uHi - uLo + 1);
    strip.x.resize(n), strip.y.resize(n), strip.z.resize(n);
    chart.rowPositions(v, uLo, uHi, heights.data() + g.index(0, v),
                       {strip.x.data(), strip.y.data(), strip.z.data()});
  };
  // Encodes a run's bounds (errors e, radii r) and stores them at first[stride * k]. Encoding
  // a run in one loop lets the table look-ups of neighbouring vertices overlap.
  auto storeCodes = [&](BoundCodes* first, std::size_t stride, std::size_t n, const double* e,
                        const double* r) {
    thread_local std::vector<std::uint16_t> errorCodes, radiusCodes;
    errorCodes.resize(n), radiusCodes.assign(n, 0);
    BoundCode::encodeUp(e, n, errorCodes.data());
    if (withRadii) BoundCode::encodeUp(r, n, radiusCodes.data());
    for (std::size_t k = 0; k < n; ++k) first[stride * k] = {errorCodes[k], radiusCodes[k]};
  };
  // Vertices uFirst, uFirst + 2, ..., uLast of row v (1 <= v < m, 1 <= uFirst, uLast < m).
  auto fineRow = [&](int v, int uFirst, int uLast) {
    thread_local RowStrip below, row, above;
    thread_local std::vector<double> radius2, error2;
    thread_local std::vector<std::uint16_t> childCodes;
    fillStrip(below, v - 1, uFirst - 1, uLast + 1);
    fillStrip(row, v, uFirst - 1, uLast + 1);
    fillStrip(above, v + 1, uFirst - 1, uLast + 1);
    const std::size_t n = std::size_t((uLast - uFirst) / 2 + 1);
    radius2.resize(n), error2.resize(n);
    const double *bx = below.x.data(), *by = below.y.data(), *bz = below.z.data();
    const double *rx = row.x.data(), *ry = row.y.data(), *rz = row.z.data();
    const double *ax = above.x.data(), *ay = above.y.data(), *az = above.z.data();
    double* r2 = radius2.data();
    double* e2 = error2.data();
    auto dist2 = [](double x0, double y0, double z0, double x1, double y1, double z1) {
      const double dx = x0 - x1, dy = y0 - y1, dz = z0 - z1;
      return dx * dx + dy * dy + dz * dz;
    };
    if (level == 0) {
      // Horizontal leaves (even rows) split between their left and right neighbours, vertical
      // ones (odd rows) between those below and above; the radius reaches all four.
      const bool horizontal = (v & 1) == 0;
      const double* b0x = horizontal ? rx - 1 : bx;
      const double* b0y = horizontal ? ry - 1 : by;
      const double* b0z = horizontal ? rz - 1 : bz;
      const double* b1x = horizontal ? rx + 1 : ax;
      const double* b1y = horizontal ? ry + 1 : ay;
      const double* b1z = horizontal ? rz + 1 : az;
#pragma omp simd
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = 2 * k + 1;
        const double px = rx[i], py = ry[i], pz = rz[i];
        const double left = dist2(rx[i - 1], ry[i - 1], rz[i - 1], px, py, pz);
        const double right = dist2(rx[i + 1], ry[i + 1], rz[i + 1], px, py, pz);
        const double down = dist2(bx[i], by[i], bz[i], px, py, pz);
        const double up = dist2(ax[i], ay[i], az[i], px, py, pz);
        const double lr = left > right ? left : right, du = down > up ? down : up;
        r2[k] = lr > du ? lr : du;
        e2[k] = dist2(px, py, pz, 0.5 * (b0x[i] + b1x[i]), 0.5 * (b0y[i] + b1y[i]),
                      0.5 * (b0z[i] + b1z[i]));
      }
#pragma omp simd
      for (std::size_t k = 0; k < n; ++k) {
        r2[k] = std::sqrt(r2[k]);
        e2[k] = std::sqrt(e2[k]);
      }
      storeCodes(codes + g.index(uFirst, v), 2, n, e2, r2);
      return;
    }
    // Level 1: centre vertices of the cells, with their children left, right, below and above
    // (their squared distances in r2 and the three arrays below); the hypotenuse is the cell's
    // main diagonal or the other one, alternating along the row.
    thread_local std::vector<double> right2, below2, above2;
    right2.resize(n), below2.resize(n), above2.resize(n);
    double* rr2 = right2.data();
    double* br2 = below2.data();
    double* ar2 = above2.data();
    const std::size_t diagonalParity = std::size_t((uFirst - 1) / 2 + (v - 1) / 2);
#pragma omp simd
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = 2 * k + 1;
      const double px = rx[i], py = ry[i], pz = rz[i];
      r2[k] = dist2(rx[i - 1], ry[i - 1], rz[i - 1], px, py, pz);
      rr2[k] = dist2(rx[i + 1], ry[i + 1], rz[i + 1], px, py, pz);
      br2[k] = dist2(bx[i], by[i], bz[i], px, py, pz);
      ar2[k] = dist2(ax[i], ay[i], az[i], px, py, pz);
      const double main = dist2(px, py, pz, 0.5 * (bx[i - 1] + ax[i + 1]),
                                0.5 * (by[i - 1] + ay[i + 1]), 0.5 * (bz[i - 1] + az[i + 1]));
      const double anti = dist2(px, py, pz, 0.5 * (bx[i + 1] + ax[i - 1]),
                                0.5 * (by[i + 1] + ay[i - 1]), 0.5 * (bz[i + 1] + az[i - 1]));
      // A bitwise select: a conditional here kept the compiler from vectorising the loop.
      const std::uint64_t takeAnti = 0 - std::uint64_t((diagonalParity + k) & 1);
      e2[k] = std::bit_cast<double>((std::bit_cast<std::uint64_t>(main) & ~takeAnti) |
                                    (std::bit_cast<std::uint64_t>(anti) & takeAnti));
    }
#pragma omp simd
    for (std::size_t k = 0; k < n; ++k) {
      r2[k] = std::sqrt(r2[k]);
      rr2[k] = std::sqrt(rr2[k]);
      br2[k] = std::sqrt(br2[k]);
      ar2[k] = std::sqrt(ar2[k]);
      e2[k] = std::sqrt(e2[k]);
    }
    const BoundCodes* codesBelow = codes + g.index(0, v - 1);
    const BoundCodes* codesAbove = codes + g.index(0, v + 1);
    BoundCodes* codesRow = codes + g.index(0, v);
    for (std::size_t k = 0; k < n; ++k) {
      const int u = uFirst + 2 * int(k);
      const BoundCodes left = codesRow[u - 1], right = codesRow[u + 1], down = codesBelow[u],
                       up = codesAbove[u];
      const std::uint16_t childCode =
          std::max(std::max(left.error, right.error), std::max(down.error, up.error));
      double radius = 0.0;
      if (withRadii) {
        auto reach = [](std::uint16_t code, double d) {
          return (double(BoundCode::decode(code)) + d) * kRadiusMargin;
        };
        radius = std::max(std::max(reach(left.radius, r2[k]), reach(right.radius, rr2[k])),
                          std::max(reach(down.radius, br2[k]), reach(up.radius, ar2[k])));
      }
      const double childEps = BoundCode::decode(childCode);
      e2[k] = rule == ErrorRule::kHybridExact ? std::max(childEps, e2[k]) : childEps + e2[k];
      r2[k] = radius;
    }
    storeCodes(codesRow + uFirst, 2, n, e2, r2);
  };

  // Levels 2 .. 5: every vertex of one row with the same orientation (edge levels: the whole
  // row; centre levels: every other vertex, the diagonals alternate) reads its children, corners
  // and scanned points at the same offsets, so the arithmetic of computeVertex runs as stencil
  // loops over strips of the rows v - s .. v + s, vertex by vertex in the inner loop. The same
  // formulas in the same order as computeVertex and the scans, so the same codes.
  // The stencil kernel for the vertices uFirst, uFirst + 2s, ... (count of them) of row v.
  auto stencilRow = [&](int v, int uFirst, std::size_t count) {
    thread_local std::array<RowStrip, 2 * kExactMaxHalfSize + 1> strips;
    const int uLo = uFirst - s, uHi = uFirst + 2 * s * int(count - 1) + s;
    for (int dv = -s; dv <= s; ++dv) fillStrip(strips[std::size_t(dv + s)], v + dv, uLo, uHi);
    auto run = [&](int runFirst, int step, std::size_t n) {
      const Diamond d = Diamond::of({runFirst, v});  // the offsets of every vertex of this run
      struct Point {
        const double *x, *y, *z;  // the run's first vertex's point; vertex k at [step * k]
      };
      auto at = [&](GridPoint q) {
        const RowStrip& strip = strips[std::size_t(q.v - v + s)];
        const std::size_t k = std::size_t(q.u - uLo);
        return Point{strip.x.data() + k, strip.y.data() + k, strip.z.data() + k};
      };
      const std::size_t st = std::size_t(step);
      const Point P = at(d.centre);
      thread_local std::array<std::vector<double>, 4> childDistance;
      thread_local std::vector<double> worst2;
      for (int c = 0; c < 4; ++c) {
        std::vector<double>& out = childDistance[std::size_t(c)];
        out.resize(n);
        double* o = out.data();
        const Point C = at(d.children[std::size_t(c)]);
#pragma omp simd
        for (std::size_t k = 0; k < n; ++k) {
          const double dx = C.x[st * k] - P.x[st * k], dy = C.y[st * k] - P.y[st * k],
                       dz = C.z[st * k] - P.z[st * k];
          o[k] = std::sqrt(dx * dx + dy * dy + dz * dz);
        }
      }
      worst2.assign(n, 0.0);
      double* w2 = worst2.data();
      const Point B0 = at(d.base0), B1 = at(d.base1);
      // Largest squared distance of q from the point (a + w0 d0) + w1 d1 (d0 = b0 - a, d1 = b1 -
      // a).
      auto accumulate = [&](const Point& Q, const Point& A, const Point& E0, const Point& E1,
                            double w0, double w1) {
#pragma omp simd
        for (std::size_t k = 0; k < n; ++k) {
          const std::size_t j = st * k;
          const double ax = A.x[j], ay = A.y[j], az = A.z[j];
          const double dx = Q.x[j] - ((ax + w0 * (E0.x[j] - ax)) + w1 * (E1.x[j] - ax));
          const double dy = Q.y[j] - ((ay + w0 * (E0.y[j] - ay)) + w1 * (E1.y[j] - ay));
          const double dz = Q.z[j] - ((az + w0 * (E0.z[j] - az)) + w1 * (E1.z[j] - az));
          const double e = dx * dx + dy * dy + dz * dz;
          w2[k] = w2[k] > e ? w2[k] : e;
        }
      };
      if (rule == ErrorRule::kHybridExact) {
        // The shared hypotenuse (v among its points): hypotenuseDeviation's p0 + t (p1 - p0).
        const int steps =
            std::max(std::abs(d.base1.u - d.base0.u), std::abs(d.base1.v - d.base0.v));
        const int du = (d.base1.u - d.base0.u) / steps, dv = (d.base1.v - d.base0.v) / steps;
        const double inv = 1.0 / steps;
        for (int j = 1; j < steps; ++j) {
          const Point Q = at({d.base0.u + j * du, d.base0.v + j * dv});
          const double t = double(j) * inv;
#pragma omp simd
          for (std::size_t k = 0; k < n; ++k) {
            const std::size_t i = st * k;
            const double dx = Q.x[i] - (B0.x[i] + t * (B1.x[i] - B0.x[i]));
            const double dy = Q.y[i] - (B0.y[i] + t * (B1.y[i] - B0.y[i]));
            const double dz = Q.z[i] - (B0.z[i] + t * (B1.z[i] - B0.z[i]));
            const double e = dx * dx + dy * dy + dz * dz;
            w2[k] = w2[k] > e ? w2[k] : e;
          }
        }
        // The two interiors (interiorDeviation's weights).
        for (auto [a, b0, b1] :
             {std::array{d.apex0, d.base0, d.base1}, std::array{d.apex1, d.base1, d.base0}}) {
          const Point A = at(a), E0 = at(b0), E1 = at(b1);
          forEachGridPointInTriangle(
              a, b0, b1,
              [&](int qu, int qv, double w0, double w1) {
                accumulate(at({qu, qv}), A, E0, E1, w0, w1);
              },
              TriangleSet::kOpen);
        }
      } else {
        // Wedgie: the midpoint error, to be added to the children's bound.
#pragma omp simd
        for (std::size_t k = 0; k < n; ++k) {
          const std::size_t i = st * k;
          const double dx = P.x[i] - 0.5 * (B0.x[i] + B1.x[i]);
          const double dy = P.y[i] - 0.5 * (B0.y[i] + B1.y[i]);
          const double dz = P.z[i] - 0.5 * (B0.z[i] + B1.z[i]);
          w2[k] = dx * dx + dy * dy + dz * dz;
        }
      }
#pragma omp simd
      for (std::size_t k = 0; k < n; ++k) w2[k] = std::sqrt(w2[k]);
      std::array<std::ptrdiff_t, 4> childOffset;
      for (std::size_t c = 0; c < 4; ++c)
        childOffset[c] = std::ptrdiff_t(g.index(d.children[c].u, d.children[c].v)) -
                         std::ptrdiff_t(g.index(runFirst, v));
      BoundCodes* first = codes + g.index(runFirst, v);
      thread_local std::vector<double> radii;
      radii.resize(n);
      double* r = radii.data();
      for (std::size_t k = 0; k < n; ++k) {
        const BoundCodes* out = first + st * k;
        std::uint16_t childCode = 0;
        double radius = 0.0;
        for (std::size_t c = 0; c < 4; ++c) {
          const BoundCodes child = out[childOffset[c]];
          childCode = std::max(childCode, child.error);
          if (withRadii) {
            radius =
                std::max(radius, (double(BoundCode::decode(child.radius)) + childDistance[c][k]) *
                                     kRadiusMargin);
          }
        }
        const double childEps = BoundCode::decode(childCode);
        w2[k] = rule == ErrorRule::kHybridExact ? std::max(childEps, w2[k]) : childEps + w2[k];
        r[k] = radius;
      }
      storeCodes(first, st, n, w2, r);
    };
    if (!centre) {
      run(uFirst, 2 * s, count);
    } else {
      // Centre levels: the diagonal alternates, so two runs of every other vertex.
      run(uFirst, 4 * s, (count + 1) / 2);
      if (count > 1) run(uFirst + 2 * s, 4 * s, count / 2);
    }
  };

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
  // costs more than the work, and much more when the machine is busy.
  const bool parallel = work > 20000.0;
  std::size_t count = 0;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : count) if (parallel)
  for (std::size_t item = 0; item < rows.size() * rangeCount; ++item) {
    const int v = rows[item / rangeCount];
    const auto [uA, uB] = ranges[item % rangeCount];
    const bool vOdd = ((v / s) & 1) != 0;
    // Columns: on an odd row, edge vertices have u/s even and centres u/s odd; on an even row
    // only edge vertices, u/s odd.
    const bool wantUOdd = centre || !vOdd;
    int u = ((uA + s - 1) / s) * s;
    if ((((u / s) & 1) != 0) != wantUOdd) u += s;
    if (s <= kExactMaxHalfSize && v >= s && v <= m - s && u <= uB) {
      // The row kernels take the vertices whose diamonds lie inside the grid; the seam columns
      // (u = 0 and u = m) take the general path.
      const int step = 2 * s;
      const int first = u == 0 ? step : u;
      int last = u + ((uB - u) / step) * step;
      const bool lastIsSeam = last == m;
      if (lastIsSeam) last -= step;
      // In chunks whose rows of positions stay in the L1/L2 caches (a whole row of level 5's
      // nine rows was 1.8 MB and every stencil loop streamed it from L3).
      constexpr int kChunk = 64;
      for (int chunkFirst = first; chunkFirst <= last; chunkFirst += kChunk * step) {
        const int chunkLast = std::min(last, chunkFirst + (kChunk - 1) * step);
        const std::size_t n = std::size_t((chunkLast - chunkFirst) / step + 1);
        if (level <= 1)
          fineRow(v, chunkFirst, chunkLast);
        else
          stencilRow(v, chunkFirst, n);
        count += n;
      }
      for (int seam : {0, m}) {
        if ((seam == 0 && u == 0) || (seam == m && lastIsSeam)) {
          level == 0 ? computeLeaf({seam, v}) : computeVertex({seam, v});
          ++count;
        }
      }
      continue;
    }
    for (; u <= uB; u += 2 * s) {
      if ((u == 0 || u == m) && (v == 0 || v == m)) continue;  // grid corners split nothing
      if (level == 0)
        computeLeaf({u, v});
      else
        computeVertex({u, v});
      if (levelOnLattice) copyToLattice(u, v);
      ++count;
    }
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
        computeVertex({0, v});
        computeVertex({m, v});
        const BoundCodes both{std::max(codes[a].error, codes[b].error),
                              std::max(codes[a].radius, codes[b].radius)};
        codes[a] = codes[b] = both;
        if (levelOnLattice) {
          copyToLattice(0, v);
          copyToLattice(m, v);
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
    latticeSide_ = (g.m() >> kLatticeShift) + 1;
    lattice_.assign(std::size_t(latticeSide_) * std::size_t(latticeSide_), LatticeEntry{});
  } else {
    latticeSide_ = 0;
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
