// Explicit drift-diffusion on the glued charts with each face weighed once (docs/SAND.md, "Each
// face weighed once"): the face's conductance times its weight (an arctangent and a division,
// most of the step's time) computed for the E and N faces of every cell of a tile and the W and
// S faces of its first column and row, then each cell's flux per face from those. The same
// operations as kernels::gluedDiffusionRow, where both cells of an inner face read the same bits
// of L / d and 1 / d, which gluedFacesShared checks once a tile.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include <cstring>

#include "sand/kernels.hpp"
#include "sand/sand_field_parts.hpp"

namespace ps::sand {

namespace {
constexpr std::size_t kCells = std::size_t(kT) * kT;

// Whether plane a at cell i and plane b at cell i + step hold the same bits, for every i of the
// tile whose cell i + step lies in the tile (step 1: along rows; kT: the next row).
bool planesAgree(const double* a, const double* b, int step) {
  for (int lv = 0; lv < kT; ++lv) {
    for (int lu = 0; lu < kT; ++lu) {
      if ((step == 1 && lu + 1 == kT) || (step == kT && lv + 1 == kT)) continue;
      const int i = lv * kT + lu;
      if (std::memcmp(a + i, b + i + step, sizeof(double)) != 0) return false;
    }
  }
  return true;
}
}  // namespace

// A cell's E face is its east neighbour's W face and its N face its north neighbour's S face
// wherever Tile::geo gives them the same L / d and 1 / d bits (away from the folds and seams
// always, SandGrid::chordBetween and the quads' centres being symmetric in the two points; not
// where a twin or no cell sits in the tile, whose planes hold 0).
bool SandField::gluedFacesShared(Tile& tile) const {
  if (tile.facesShared == 0) {
    const double* geo = tile.geo.get();
    auto plane = [geo](int p) { return geo + std::size_t(p) * kCells; };
    const bool shared = planesAgree(plane(kGeoRatio + 1), plane(kGeoRatio + 0), 1) &&
                        planesAgree(plane(kGeoInv + 1), plane(kGeoInv + 0), 1) &&
                        planesAgree(plane(kGeoRatio + 3), plane(kGeoRatio + 2), kT) &&
                        planesAgree(plane(kGeoInv + 3), plane(kGeoInv + 2), kT);
    tile.facesShared = shared ? 1 : 2;
  }
  return tile.facesShared == 1;
}

// The tile's new heights (its cur) from the scratch heights hs (a one-cell halo at least),
// row by row: the faces below a row are the faces above the row before.
unsigned SandField::diffusionGluedFaces(Tile& tile, const double* hs, const DiffusionTables& tb,
                                        double Dl2, double dt) const {
  const double* geo = tile.geo.get();
  auto plane = [geo](int p, int lv) {
    return geo + std::size_t(p) * kCells + std::size_t(lv) * kT;
  };
  double faces[3][kT + 1];  // W of the first cell and E of each; below; above
  double* wS = faces[1];
  double* wN = faces[2];
  const double* first = hs + 2 * kW + 2;
  kernels::gluedFaceWeights(first, first - kW, plane(kGeoRatio + 2, 0), plane(kGeoInv + 2, 0), wS,
                            kT, Dl2, tb.repose);
  unsigned any = 0;
  for (int lv = 0; lv < kT; ++lv) {
    const double* h0 = hs + (lv + 2) * kW + 2;
    kernels::gluedFaceWeights(h0, h0 - 1, plane(kGeoRatio + 0, lv), plane(kGeoInv + 0, lv),
                              faces[0], 1, Dl2, tb.repose);
    kernels::gluedFaceWeights(h0, h0 + 1, plane(kGeoRatio + 1, lv), plane(kGeoInv + 1, lv),
                              faces[0] + 1, kT, Dl2, tb.repose);
    kernels::gluedFaceWeights(h0, h0 + kW, plane(kGeoRatio + 3, lv), plane(kGeoInv + 3, lv), wN, kT,
                              Dl2, tb.repose);
    any |= kernels::gluedDiffusionFromFaces(h0 - kW, h0, h0 + kW, tile.cur.get() + lv * kT,
                                            faces[0], wS, wN, plane(kGeoArea, lv), dt);
    std::swap(wS, wN);
  }
  return any;
}

}  // namespace ps::sand
