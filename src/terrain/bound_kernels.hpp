#pragma once
// The row kernels of ErrorBounds (error_bounds.cpp includes this; nothing else should).
//
// Levels 0 .. 5 are 63/64 of all vertices, and every vertex whose diamond lies inside the grid
// reads its children, corners and scanned points at the same offsets as its neighbours on the
// row: the per-vertex arithmetic of the scalar path (vertex_bounds.hpp) runs here as loops over a
// run of a row's vertices, on positions computed once per row (Chart::rowPositions) instead of
// afresh for every vertex that reads them, with the square roots and encodings of a run in loops of
// their own. The formulas and their order are the scalar path's, so the codes are the ones the
// scalar path gave (the checksums of whole planets did not move; a code from a squared distance
// differs from the code of its rounded root only where that root is exactly a code's value).
// The scalar path stays for the vertices on the grid's edges and the seam; which path a vertex
// takes depends on its position alone, so a local update equals a full rebuild bit for bit.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/grid.hpp"
#include "terrain/bound_code.hpp"
#include "terrain/diamond.hpp"
#include "terrain/error_bounds.hpp"
#include "terrain/position_boxes.hpp"

namespace ps::terrain::detail {

// A nested radius must exceed its child's by a margin, so that the view-dependent test, which
// is evaluated in floating point, stays monotone from child to parent even when a child's ball
// touches its parent's from inside.
constexpr double kRadiusMargin = 1.0 + 1e-7;

template <class ChartT>
class BoundKernels {
  // On a flat chart x and y are linear in (u, v), so a scanned deviation is the height's alone
  // (interiorDeviation's), without the planar components' rounding noise.
  static constexpr bool kFlat = std::is_same_v<ChartT, core::FlatChart>;

 public:
  // boxes: positions computed beforehand (null: none).
  BoundKernels(const ChartT& chart, const float* heights, BoundCodes* codes, int level,
               ErrorRule rule, bool withRadii, const PositionBoxes* boxes = nullptr)
      : chart_(chart),
        boxes_(boxes),
        g_(chart.grid()),
        heights_(heights),
        codes_(codes),
        level_(level),
        s_(levelHalfSize(level)),
        centre_(levelIsCentre(level)),
        rule_(rule),
        withRadii_(withRadii) {}

  // Rows of positions are kept per thread for the next rows to share (a band of rows of one
  // level reads rows v - s .. v + s each). Call at the start of each work item: the heights may
  // have changed since the rows were read.
  void forgetRows() const {
    for (CachedRow& row : scratch().rows) row.v = -1;
  }
  // Level 0 or 1: the vertices uFirst, uFirst + 2, ..., uLast of row v, 1 <= v < m,
  // 1 <= uFirst <= uLast < m (all four neighbours in the grid).
  void fineRow(int v, int uFirst, int uLast) const;
  // Levels 2 .. 5: `count` vertices from uFirst on, 2s apart, on row v; their diamonds inside the
  // grid (s <= v <= m - s, s <= u <= m - s).
  void stencilRow(int v, int uFirst, std::size_t count) const;

 private:
  struct CachedRow {  // positions of row v's columns uLo .. uHi, kept for the next runs
    int v = -1, uLo = 0, uHi = -1;
    std::vector<double> x, y, z;
  };
  // Positions in three arrays: a row's (column u at [u - the uLo asked for]), or one offset's of
  // a run (the first vertex's point at [0], vertex k's at [step * k]).
  struct Positions {
    const double *x, *y, *z;
  };
  struct Scratch {                   // per thread, reused from run to run
    std::array<CachedRow, 16> rows;  // row v in rows[v % 16]: the 2s + 1 <= 9 rows a run reads
                                     // and the next run's are distinct
    std::array<std::vector<double>, 5> distances;  // children, then the error
    std::array<std::vector<double>, 9> frame;      // a triangle's corner and edge vectors
    std::vector<double> radii;
    std::vector<std::uint16_t> childCodes, errorCodes, radiusCodes;
  };
  static Scratch& scratch() {
    thread_local Scratch s;
    return s;
  }

  // Row v's positions over columns uLo .. uHi (within the grid), computed unless kept.
  Positions row(int v, int uLo, int uHi) const {
    if (boxes_) {
      const PositionBoxes::Row r = boxes_->row(v, uLo, uHi);
      if (r.x) return {r.x, r.y, r.z};
    }
    CachedRow& kept = scratch().rows[std::size_t(v) & 15];
    if (kept.v != v || kept.uLo > uLo || kept.uHi < uHi) {
      // One column more on each side: level 0's rows of the other parity ask one column
      // further along.
      kept.v = v, kept.uLo = std::max(0, uLo - 1), kept.uHi = std::min(g_.m(), uHi + 1);
      const std::size_t n = std::size_t(kept.uHi - kept.uLo + 1);
      kept.x.resize(n), kept.y.resize(n), kept.z.resize(n);
      chart_.rowPositions(v, kept.uLo, kept.uHi, heights_ + g_.index(0, v),
                          {kept.x.data(), kept.y.data(), kept.z.data()});
    }
    const std::size_t shift = std::size_t(uLo - kept.uLo);
    return {kept.x.data() + shift, kept.y.data() + shift, kept.z.data() + shift};
  }
  static double dist2(double x0, double y0, double z0, double x1, double y1, double z1) {
    const double dx = x0 - x1, dy = y0 - y1, dz = z0 - z1;
    return dx * dx + dy * dy + dz * dz;
  }
  static void sqrtAll(std::vector<double>& values, std::size_t n) {
    double* p = values.data();
#pragma omp simd
    for (std::size_t k = 0; k < n; ++k) p[k] = std::sqrt(p[k]);
  }
  // A run's bounds, encoded into first[stride * k]: errors and radii from their values, or from
  // their squares where the flag says so (BoundCode::encodeUpFromSquare), the error code raised
  // to atLeast[k] where atLeast is given (the hybrid rule's max with the children: encoding is
  // monotone and encodeUp(decode(c)) == c). Encoding a run in one loop lets it vectorise.
  struct Values {
    const double* values;
    bool squared;
  };
  void store(BoundCodes* first, std::size_t stride, std::size_t n, Values errors,
             const std::uint16_t* atLeast, Values radii) const;
  // Errors from the largest squared deviations `own` and the children's codes: under the hybrid
  // rule max(children, sqrt(own)), as codes; under the wedgie rule children + sqrt(own).
  void storeWithChildren(BoundCodes* first, std::size_t stride, std::size_t n,
                         std::vector<double>& own, const std::uint16_t* childCodes,
                         const double* radii) const {
    if (rule_ == ErrorRule::kHybridExact) {
      store(first, stride, n, {own.data(), true}, childCodes, {radii, false});
      return;
    }
    sqrtAll(own, n);
    for (std::size_t k = 0; k < n; ++k) own[k] += double(BoundCode::decode(childCodes[k]));
    store(first, stride, n, {own.data(), false}, nullptr, {radii, false});
  }
  static double reach(std::uint16_t radiusCode, double distance) {
    return (double(BoundCode::decode(radiusCode)) + distance) * kRadiusMargin;
  }
  using Rows = std::array<Positions, 2 * ErrorBounds::kExactMaxHalfSize + 1>;
  void stencilRun(const Rows& rows, int v, int runFirst, std::size_t step, std::size_t n,
                  int uLo) const;

  const ChartT& chart_;
  const PositionBoxes* boxes_;
  core::GridSize g_;
  const float* heights_;
  BoundCodes* codes_;
  int level_, s_;
  bool centre_;
  ErrorRule rule_;
  bool withRadii_;
};

template <class ChartT>
void BoundKernels<ChartT>::store(BoundCodes* first, std::size_t stride, std::size_t n,
                                 Values errors, const std::uint16_t* atLeast, Values radii) const {
  Scratch& w = scratch();
  w.errorCodes.resize(n), w.radiusCodes.assign(n, 0);
  auto encode = [n](Values in, std::uint16_t* out) {
    if (in.squared)
      BoundCode::encodeUpFromSquare(in.values, n, out);
    else
      BoundCode::encodeUp(in.values, n, out);
  };
  encode(errors, w.errorCodes.data());
  if (withRadii_) encode(radii, w.radiusCodes.data());
  if (atLeast) {
    for (std::size_t k = 0; k < n; ++k) w.errorCodes[k] = std::max(w.errorCodes[k], atLeast[k]);
  }
  for (std::size_t k = 0; k < n; ++k) first[stride * k] = {w.errorCodes[k], w.radiusCodes[k]};
}

template <class ChartT>
void BoundKernels<ChartT>::fineRow(int v, int uFirst, int uLast) const {
  Scratch& w = scratch();
  const Positions below = row(v - 1, uFirst - 1, uLast + 1), here = row(v, uFirst - 1, uLast + 1),
                  above = row(v + 1, uFirst - 1, uLast + 1);
  const std::size_t n = std::size_t((uLast - uFirst) / 2 + 1);
  for (auto& d : w.distances) d.resize(n);
  const double *bx = below.x, *by = below.y, *bz = below.z;
  const double *rx = here.x, *ry = here.y, *rz = here.z;
  const double *ax = above.x, *ay = above.y, *az = above.z;
  // Vertex k sits at the row's index 2k + 1; its neighbours left, right, below and above.
  double* left = w.distances[0].data();
  double* right = w.distances[1].data();
  double* down = w.distances[2].data();
  double* up = w.distances[3].data();
  double* e = w.distances[4].data();
  if (level_ == 0) {
    // computeLeaf: horizontal leaves (even rows) split between their left and right
    // neighbours, vertical ones (odd rows) between those below and above; the radius reaches
    // all four. Both are encoded from their squares.
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
      const double l = dist2(rx[i - 1], ry[i - 1], rz[i - 1], px, py, pz);
      const double r = dist2(rx[i + 1], ry[i + 1], rz[i + 1], px, py, pz);
      const double d = dist2(bx[i], by[i], bz[i], px, py, pz);
      const double u = dist2(ax[i], ay[i], az[i], px, py, pz);
      const double lr = l > r ? l : r, du = d > u ? d : u;
      left[k] = lr > du ? lr : du;
      e[k] = dist2(px, py, pz, 0.5 * (b0x[i] + b1x[i]), 0.5 * (b0y[i] + b1y[i]),
                   0.5 * (b0z[i] + b1z[i]));
    }
    store(codes_ + g_.index(uFirst, v), 2, n, {e, true}, nullptr, {left, true});
    return;
  }
  // Level 1 (computeVertex): centre vertices of the cells, children left, right, below and
  // above; the hypotenuse is the cell's main diagonal or the other one, alternating along the
  // row.
  const std::size_t diagonalParity = std::size_t((uFirst - 1) / 2 + (v - 1) / 2);
#pragma omp simd
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = 2 * k + 1;
    const double px = rx[i], py = ry[i], pz = rz[i];
    left[k] = dist2(rx[i - 1], ry[i - 1], rz[i - 1], px, py, pz);
    right[k] = dist2(rx[i + 1], ry[i + 1], rz[i + 1], px, py, pz);
    down[k] = dist2(bx[i], by[i], bz[i], px, py, pz);
    up[k] = dist2(ax[i], ay[i], az[i], px, py, pz);
    const double main = dist2(px, py, pz, 0.5 * (bx[i - 1] + ax[i + 1]),
                              0.5 * (by[i - 1] + ay[i + 1]), 0.5 * (bz[i - 1] + az[i + 1]));
    const double anti = dist2(px, py, pz, 0.5 * (bx[i + 1] + ax[i - 1]),
                              0.5 * (by[i + 1] + ay[i - 1]), 0.5 * (bz[i + 1] + az[i - 1]));
    // A bitwise select: a conditional here kept the compiler from vectorising the loop.
    const std::uint64_t takeAnti = 0 - std::uint64_t((diagonalParity + k) & 1);
    e[k] = std::bit_cast<double>((std::bit_cast<std::uint64_t>(main) & ~takeAnti) |
                                 (std::bit_cast<std::uint64_t>(anti) & takeAnti));
  }
  for (std::size_t c = 0; c < 4; ++c) sqrtAll(w.distances[c], n);
  w.childCodes.resize(n);
  const BoundCodes* codesBelow = codes_ + g_.index(0, v - 1);
  const BoundCodes* codesAbove = codes_ + g_.index(0, v + 1);
  BoundCodes* codesRow = codes_ + g_.index(0, v);
  for (std::size_t k = 0; k < n; ++k) {
    const int u = uFirst + 2 * int(k);
    const BoundCodes l = codesRow[u - 1], r = codesRow[u + 1], d = codesBelow[u], a = codesAbove[u];
    w.childCodes[k] = std::max(std::max(l.error, r.error), std::max(d.error, a.error));
    const double radius =
        withRadii_ ? std::max(std::max(reach(l.radius, left[k]), reach(r.radius, right[k])),
                              std::max(reach(d.radius, down[k]), reach(a.radius, up[k])))
                   : 0.0;
    left[k] = radius;
  }
  storeWithChildren(codesRow + uFirst, 2, n, w.distances[4], w.childCodes.data(), left);
}

template <class ChartT>
void BoundKernels<ChartT>::stencilRow(int v, int uFirst, std::size_t count) const {
  const int s = s_;
  const int uLo = uFirst - s, uHi = uFirst + 2 * s * int(count - 1) + s;
  Rows rows;  // rows v - s .. v + s
  for (int dv = -s; dv <= s; ++dv) rows[std::size_t(dv + s)] = row(v + dv, uLo, uHi);
  if (!centre_) {
    stencilRun(rows, v, uFirst, std::size_t(2 * s), count, uLo);
  } else {
    // Centre levels: the diagonal alternates, so two runs of every other vertex.
    stencilRun(rows, v, uFirst, std::size_t(4 * s), (count + 1) / 2, uLo);
    if (count > 1) stencilRun(rows, v, uFirst + 2 * s, std::size_t(4 * s), count / 2, uLo);
  }
}

template <class ChartT>
void BoundKernels<ChartT>::stencilRun(const Rows& rows, int v, int runFirst, std::size_t st,
                                      std::size_t n, int uLo) const {
  Scratch& w = scratch();
  const int s = s_;
  const Diamond d = Diamond::of({runFirst, v});  // the offsets of every vertex of this run
  auto at = [&](GridPoint q) {
    const Positions& r = rows[std::size_t(q.v - v + s)];
    const std::size_t k = std::size_t(q.u - uLo);
    return Positions{r.x + k, r.y + k, r.z + k};
  };
  const Positions P = at(d.centre);
  // Distances to the four children.
  for (std::size_t c = 0; c < 4; ++c) {
    w.distances[c].resize(n);
    double* o = w.distances[c].data();
    const Positions C = at(d.children[c]);
#pragma omp simd
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t j = st * k;
      o[k] = std::sqrt(dist2(C.x[j], C.y[j], C.z[j], P.x[j], P.y[j], P.z[j]));
    }
  }
  w.distances[4].assign(n, 0.0);
  double* worst = w.distances[4].data();  // largest squared deviation so far
  const Positions B0 = at(d.base0), B1 = at(d.base1);
  if (rule_ == ErrorRule::kHybridExact) {
    // The triangle being scanned: corner a, edge vectors d0 = b0 - a and d1 = b1 - a. With s = 4
    // (9-21 points per triangle) they are written once per triangle, vertex by vertex
    // (contiguous: every scanned point reads them); with s = 2 (1-3 points) that costs more
    // than it saves and the points read the corners from the cached rows. The same arithmetic.
    const bool framed = s >= 4;
    Positions A{}, E0{}, E1{};
    auto setFrame = [&](const Positions& a, const Positions& e0, const Positions& e1) {
      A = a, E0 = e0, E1 = e1;
      if (!framed) return;
      for (auto& f : w.frame) f.resize(n);
      double *ax = w.frame[0].data(), *ay = w.frame[1].data(), *az = w.frame[2].data();
      double *d0x = w.frame[3].data(), *d0y = w.frame[4].data(), *d0z = w.frame[5].data();
      double *d1x = w.frame[6].data(), *d1y = w.frame[7].data(), *d1z = w.frame[8].data();
#pragma omp simd
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t j = st * k;
        ax[k] = a.x[j], ay[k] = a.y[j], az[k] = a.z[j];
        d0x[k] = e0.x[j] - a.x[j], d0y[k] = e0.y[j] - a.y[j], d0z[k] = e0.z[j] - a.z[j];
        d1x[k] = e1.x[j] - a.x[j], d1y[k] = e1.y[j] - a.y[j], d1z[k] = e1.z[j] - a.z[j];
      }
    };
    // The squared distance of q from (a + w0 d0) + w1 d1, maxed into worst (on a flat chart the
    // height's alone).
    auto deviation2 = [](double qx, double qy, double qz, double ax, double ay, double az,
                         double d0x, double d0y, double d0z, double d1x, double d1y, double d1z,
                         double w0, double w1) {
      const double dz = qz - ((az + w0 * d0z) + w1 * d1z);
      if constexpr (kFlat) return dz * dz;
      const double dx = qx - ((ax + w0 * d0x) + w1 * d1x);
      const double dy = qy - ((ay + w0 * d0y) + w1 * d1y);
      return dx * dx + dy * dy + dz * dz;
    };
    auto accumulate = [&](const Positions& Q, double w0, double w1) {
      if (framed) {
        const double *ax = w.frame[0].data(), *ay = w.frame[1].data(), *az = w.frame[2].data();
        const double *d0x = w.frame[3].data(), *d0y = w.frame[4].data(), *d0z = w.frame[5].data();
        const double *d1x = w.frame[6].data(), *d1y = w.frame[7].data(), *d1z = w.frame[8].data();
#pragma omp simd
        for (std::size_t k = 0; k < n; ++k) {
          const std::size_t j = st * k;
          const double e = deviation2(Q.x[j], Q.y[j], Q.z[j], ax[k], ay[k], az[k], d0x[k], d0y[k],
                                      d0z[k], d1x[k], d1y[k], d1z[k], w0, w1);
          worst[k] = worst[k] > e ? worst[k] : e;
        }
        return;
      }
#pragma omp simd
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t j = st * k;
        const double e = deviation2(Q.x[j], Q.y[j], Q.z[j], A.x[j], A.y[j], A.z[j],
                                    E0.x[j] - A.x[j], E0.y[j] - A.y[j], E0.z[j] - A.z[j],
                                    E1.x[j] - A.x[j], E1.y[j] - A.y[j], E1.z[j] - A.z[j], w0, w1);
        worst[k] = worst[k] > e ? worst[k] : e;
      }
    };
    // The shared hypotenuse (v among its points): hypotenuseDeviation's b0 + t (b1 - b0), as
    // the frame (b0, b1, b0) with weights (t, 0) (adding 0 * 0 changes no bit).
    setFrame(B0, B1, B0);
    const int steps = std::max(std::abs(d.base1.u - d.base0.u), std::abs(d.base1.v - d.base0.v));
    const int du = (d.base1.u - d.base0.u) / steps, dv = (d.base1.v - d.base0.v) / steps;
    const double inv = 1.0 / steps;
    for (int j = 1; j < steps; ++j)
      accumulate(at({d.base0.u + j * du, d.base0.v + j * dv}), double(j) * inv, 0.0);
    // The two interiors (interiorDeviation's weights); the legs are the children's.
    for (auto [a, b0, b1] :
         {std::array{d.apex0, d.base0, d.base1}, std::array{d.apex1, d.base1, d.base0}}) {
      setFrame(at(a), at(b0), at(b1));
      forEachGridPointInTriangle(
          a, b0, b1,
          [&](int qu, int qv, double w0, double w1) {
            accumulate(at({qu, qv}), w0, w1);
          },
          TriangleSet::kOpen);
    }
  } else {
    // Wedgie: the midpoint error, added to the children's bound.
#pragma omp simd
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t j = st * k;
      worst[k] = dist2(P.x[j], P.y[j], P.z[j], 0.5 * (B0.x[j] + B1.x[j]), 0.5 * (B0.y[j] + B1.y[j]),
                       0.5 * (B0.z[j] + B1.z[j]));
    }
  }
  std::array<std::ptrdiff_t, 4> childOffset;
  for (std::size_t c = 0; c < 4; ++c) {
    childOffset[c] = std::ptrdiff_t(g_.index(d.children[c].u, d.children[c].v)) -
                     std::ptrdiff_t(g_.index(runFirst, v));
  }
  BoundCodes* first = codes_ + g_.index(runFirst, v);
  w.radii.resize(n), w.childCodes.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const BoundCodes* vertex = first + st * k;
    std::uint16_t childCode = 0;
    double radius = 0.0;
    for (std::size_t c = 0; c < 4; ++c) {
      const BoundCodes child = vertex[childOffset[c]];
      childCode = std::max(childCode, child.error);
      if (withRadii_) radius = std::max(radius, reach(child.radius, w.distances[c][k]));
    }
    w.childCodes[k] = childCode;
    w.radii[k] = radius;
  }
  storeWithChildren(first, st, n, w.distances[4], w.childCodes.data(), w.radii.data());
}

}  // namespace ps::terrain::detail
