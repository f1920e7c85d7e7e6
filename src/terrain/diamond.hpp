#pragma once
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>

#include "core/grid.hpp"

namespace ps::terrain {

using core::GridPoint;

// The 4-8 hierarchy over a (2^n+1)^2 grid, by vertex arithmetic. The two root triangles split
// the square along its main diagonal; every other vertex is the midpoint of the hypotenuse
// shared by two right isosceles triangles (its diamond). With s the largest power of two
// dividing both u and v:
//   edge vertex   (exactly one of u/s, v/s odd): midpoint of an axis-aligned edge of length 2s;
//                 its diamond is the rotated square with corners (u+-s, v), (u, v+-s).
//   centre vertex (both odd): centre of the square [u-s, u+s] x [v-s, v+s]; its hypotenuse is
//                 the main diagonal when ((u-s)/2s + (v-s)/2s) is even, the anti-diagonal else.
// Levels count up from the leaves: an edge vertex with s = 2^k has level 2k, a centre vertex
// 2k+1; the root (m/2, m/2) has level 2n-1. A vertex's children (the split vertices of its four
// sub-triangles) are one level down, its two parents (the apexes of its diamond) one level up.
struct Diamond {
  GridPoint centre;
  int s = 0;  // half-size
  bool isCentre = false;
  int level = 0;
  GridPoint base0, base1;  // hypotenuse ends
  GridPoint apex0, apex1;  // the two other corners (the parents); may lie outside the grid
  int childCount = 0;
  std::array<GridPoint, 4> children{};  // may lie outside the grid

  // p must be a split vertex: not one of the four grid corners, coordinates in [0, m].
  static Diamond of(GridPoint p) {
    Diamond d;
    d.centre = p;
    const unsigned tu = p.u == 0 ? 31u : unsigned(std::countr_zero(unsigned(p.u)));
    const unsigned tv = p.v == 0 ? 31u : unsigned(std::countr_zero(unsigned(p.v)));
    const unsigned k = tu < tv ? tu : tv;
    const int s = 1 << k;
    d.s = s;
    const bool uOdd = ((p.u >> k) & 1) != 0, vOdd = ((p.v >> k) & 1) != 0;
    d.isCentre = uOdd && vOdd;
    d.level = int(2 * k) + (d.isCentre ? 1 : 0);
    const int u = p.u, v = p.v;
    if (d.isCentre) {
      const bool mainDiagonal = ((((u - s) / (2 * s)) + ((v - s) / (2 * s))) & 1) == 0;
      if (mainDiagonal) {
        d.base0 = {u - s, v - s}, d.base1 = {u + s, v + s};
        d.apex0 = {u + s, v - s}, d.apex1 = {u - s, v + s};
      } else {
        d.base0 = {u + s, v - s}, d.base1 = {u - s, v + s};
        d.apex0 = {u - s, v - s}, d.apex1 = {u + s, v + s};
      }
      d.childCount = 4;
      d.children = {GridPoint{u - s, v}, GridPoint{u + s, v}, GridPoint{u, v - s},
                    GridPoint{u, v + s}};
    } else {
      if (uOdd) {  // horizontal edge
        d.base0 = {u - s, v}, d.base1 = {u + s, v};
        d.apex0 = {u, v - s}, d.apex1 = {u, v + s};
      } else {  // vertical edge
        d.base0 = {u, v - s}, d.base1 = {u, v + s};
        d.apex0 = {u - s, v}, d.apex1 = {u + s, v};
      }
      if (s >= 2) {
        const int h = s / 2;
        d.childCount = 4;
        d.children = {GridPoint{u - h, v - h}, GridPoint{u + h, v - h}, GridPoint{u - h, v + h},
                      GridPoint{u + h, v + h}};
      }
    }
    return d;
  }
};

// Number of levels of split vertices on a grid of 2^n cells: 0 .. 2n-1.
inline int levelCount(const core::GridSize& g) {
  return 2 * g.n();
}

// Half-size and kind of the vertices of a level.
inline int levelHalfSize(int level) {
  return 1 << (level / 2);
}
inline bool levelIsCentre(int level) {
  return (level & 1) != 0;
}

// The grid points of the right isosceles triangle (a, b0, b1), right angle at a, row by row:
// f(v, uFirst, uLast, da, db, stepA, stepB) for each row v that holds any, where da and db are
// the integer barycentric numerators of b0 and b1 at uFirst (the weights are da / len2 and
// db / len2, len2 = |b0 - a|^2) and advance by stepA and stepB per column. The span is solved
// from the three edge inequalities, so no point outside the triangle is visited (the bounding
// box holds twice as many, and testing each was a branch the scans mispredicted). With
// kOpen, only the points strictly inside the triangle (none on its edges).
enum class TriangleSet { kClosed, kOpen };
template <class F>
void forEachRowSpanInTriangle(GridPoint a, GridPoint b0, GridPoint b1, F&& f,
                              TriangleSet set = TriangleSet::kClosed) {
  const long long inset = set == TriangleSet::kOpen ? 1 : 0;
  const long long e0u = b0.u - a.u, e0v = b0.v - a.v, e1u = b1.u - a.u, e1v = b1.v - a.v;
  const long long len2 = e0u * e0u + e0v * e0v;  // legs are equal
  const int u0 = std::min({a.u, b0.u, b1.u}), u1 = std::max({a.u, b0.u, b1.u});
  const int v0 = std::min({a.v, b0.v, b1.v}), v1 = std::max({a.v, b0.v, b1.v});
  // Narrows [lo, hi] (offsets from u0) to where c + k * offset >= inset.
  auto clip = [inset](long long c, long long k, long long& lo, long long& hi) {
    c -= inset;
    if (k == 0) {
      if (c < 0) hi = -1;
    } else if (k > 0) {
      lo = std::max(lo, c >= 0 ? 0 : (-c + k - 1) / k);
    } else {
      hi = c < 0 ? -1 : std::min(hi, c / -k);
    }
  };
  for (int v = v0; v <= v1; ++v) {
    const long long da = (u0 - a.u) * e0u + (v - a.v) * e0v;
    const long long db = (u0 - a.u) * e1u + (v - a.v) * e1v;
    long long lo = 0, hi = u1 - u0;
    clip(da, e0u, lo, hi);
    clip(db, e1u, lo, hi);
    clip(len2 - da - db, -(e0u + e1u), lo, hi);
    if (lo > hi) continue;
    f(v, int(u0 + lo), int(u0 + hi), da + lo * e0u, db + lo * e1u, e0u, e1u);
  }
}

// Calls f(u, v, wb0, wb1) for every grid point of the right isosceles triangle (a, b0, b1), right
// angle at a, where wb0, wb1 are the point's barycentric weights of b0 and b1 (a's is the rest).
template <class F>
void forEachGridPointInTriangle(GridPoint a, GridPoint b0, GridPoint b1, F&& f,
                                TriangleSet set = TriangleSet::kClosed) {
  const long long e0u = b0.u - a.u, e0v = b0.v - a.v;
  const double inv = 1.0 / double(e0u * e0u + e0v * e0v);
  forEachRowSpanInTriangle(
      a, b0, b1,
      [&](int v, int uFirst, int uLast, long long da, long long db, long long stepA,
          long long stepB) {
        for (int u = uFirst; u <= uLast; ++u, da += stepA, db += stepB)
          f(u, v, double(da) * inv, double(db) * inv);
      },
      set);
}

inline bool inGrid(const core::GridSize& g, GridPoint p) {
  return p.u >= 0 && p.v >= 0 && p.u <= g.m() && p.v <= g.m();
}

}  // namespace ps::terrain
