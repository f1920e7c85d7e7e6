// Explicit drift-diffusion on the glued charts with each face weighed once (docs/SAND.md, "Each
// face weighed once"): the face's conductance times its weight (an arctangent and a division,
// most of the step's time) computed for the E and N faces of every cell of a tile and the W and
// S faces of its first column and row, then each cell's flux per face from those. The same
// operations as kernels::gluedDiffusionRow, where both cells of a face read the same bits of
// L / d and 1 / d, which gluedFacesShared checks once a tile, row by row; where they do not (by
// a fold, a twin or a cone point) the row's W or S faces are weighed from its own planes.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include <cstring>
#include <utility>

#include "sand/kernels.hpp"
#include "sand/sand_field_parts.hpp"

namespace ps::sand {

namespace {
constexpr std::size_t kCells = std::size_t(kT) * kT;

// Whether plane a at cell i and plane b at cell i + step (1: the next cell of the row, kT: of
// the next row) hold the same bits, for the cells i from `first` to `last` (both in the tile).
bool planesAgree(const double* a, const double* b, int step, int first, int last) {
  for (int i = first; i <= last; ++i) {
    if (std::memcmp(a + i, b + i + step, sizeof(double)) != 0) return false;
  }
  return true;
}
}  // namespace

// A cell's E face is its east neighbour's W face and its N face its north neighbour's S face
// wherever Tile::geo gives them the same L / d and 1 / d bits (away from the folds and seams
// always, SandGrid::chordBetween and the quads' centres being symmetric in the two points; not
// where a twin or no cell sits in the tile, whose planes hold 0).
bool SandField::gluedFacesShared(Tile& tile) const {
  if (!tile.facesKnown) {
    const double* geo = tile.geo.get();
    auto plane = [geo](int p) { return geo + std::size_t(p) * kCells; };
    tile.sharedE = tile.sharedN = 0;
    for (int lv = 0; lv < kT; ++lv) {
      const int a = lv * kT;
      if (planesAgree(plane(kGeoRatio + 1), plane(kGeoRatio + 0), 1, a, a + kT - 2) &&
          planesAgree(plane(kGeoInv + 1), plane(kGeoInv + 0), 1, a, a + kT - 2))
        tile.sharedE |= 1u << lv;
      if (lv + 1 < kT &&
          planesAgree(plane(kGeoRatio + 3), plane(kGeoRatio + 2), kT, a, a + kT - 1) &&
          planesAgree(plane(kGeoInv + 3), plane(kGeoInv + 2), kT, a, a + kT - 1))
        tile.sharedN |= 1u << lv;
    }
    tile.facesKnown = true;
  }
  return tile.sharedE != 0 || tile.sharedN != 0;
}

// The tile's new heights (its cur) from the scratch heights hs (a one-cell halo at least),
// row by row: the faces below a row are the faces above the row before where shared.
unsigned SandField::diffusionGluedFaces(Tile& tile, const double* hs, const DiffusionTables& tb,
                                        double Dl2, double dt) const {
  const double* geo = tile.geo.get();
  auto plane = [geo](int p, int lv) {
    return geo + std::size_t(p) * kCells + std::size_t(lv) * kT;
  };
  auto weigh = [&](const double* a, const double* b, int p, int lv, double* gw, int n) {
    kernels::gluedFaceWeights(a, b, plane(kGeoRatio + p, lv), plane(kGeoInv + p, lv), gw, n, Dl2,
                              tb.repose);
  };
  double wWE[kT + 1], wW[kT], wS[kT], wN[kT];  // wWE: W of the first cell, E of each
  double* below = wS;
  double* above = wN;
  unsigned any = 0;
  for (int lv = 0; lv < kT; ++lv) {
    const double* h0 = hs + (lv + 2) * kW + 2;
    if (lv == 0 || !(tile.sharedN >> (lv - 1) & 1u)) weigh(h0, h0 - kW, 2, lv, below, kT);
    const bool sharedE = tile.sharedE >> lv & 1u;
    weigh(h0, h0 - 1, 0, lv, sharedE ? wWE : wW, sharedE ? 1 : kT);
    weigh(h0, h0 + 1, 1, lv, wWE + 1, kT);
    weigh(h0, h0 + kW, 3, lv, above, kT);
    any |= kernels::gluedDiffusionFromFaces(h0 - kW, h0, h0 + kW, tile.cur.get() + lv * kT,
                                            sharedE ? wWE : wW, wWE + 1, below, above,
                                            plane(kGeoArea, lv), dt);
    std::swap(below, above);
  }
  return any;
}

}  // namespace ps::sand
