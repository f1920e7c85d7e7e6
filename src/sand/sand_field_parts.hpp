#pragma once
// SandField's private parts, shared by the files that implement it (sand_field.cpp: storage and
// output; sand_active_set.cpp; sand_thermal.cpp; sand_diffusion.cpp; sand_semi_implicit.cpp);
// nothing else should include this.
#include <cstdint>
#include <memory>
#include <vector>

#include "sand/kernels.hpp"
#include "sand/sand_field.hpp"

namespace ps::sand {

namespace detail {

inline constexpr int kT = SandField::kTile;
inline constexpr int kW = kernels::kScratch;  // scratch row stride: the tile and 2 cells each side
static_assert(kW == kT + 4);
inline constexpr double kWall = kernels::kWall;
inline constexpr double kNever = 1e300;  // threshold of a link that does not exist
// Steps over fewer tiles run on one thread: a fork/join costs more than a few tiles of work
// (milliseconds when the cores are shared and a waiting thread is descheduled).
inline constexpr int kParallelTiles = 64;

}  // namespace detail

using detail::kNever;
using detail::kParallelTiles;
using detail::kT;
using detail::kW;
using detail::kWall;

// A tile's heights are updated in place; before a step writes any tile, every tile of the step
// copies its two outermost rows and columns (`edge`), and neighbours read their halo from there.
// `next` exists only for the semi-implicit step (allocated on first use).
struct SandField::Tile {
  std::unique_ptr<double[]> cur, next;
  // rows 0, 1, detail::kT-2, detail::kT-1 (4 x detail::kT), then columns 0, 1, detail::kT-2,
  // detail::kT-1 (4 x detail::kT, by row)
  std::unique_ptr<double[]> edge;
  bool unwritten = false;  // cur may differ from the floats
  // Glued charts (sand_glued.cpp): the per-cell geometry, loaded with the tile (the planes
  // below: chords, faces over chords, areas, caps), each detail::kT^2 by cell; min over its cells
  // of A / sum_f (L_f / d_f) (the explicit bound times D l^2); and the thermal outflow scale s of
  // the step (pass 1).
  std::unique_ptr<double[]> geo, s;
  double boundFactor = 0.0;
  std::vector<int> linked;  // glued: the other tiles its cells have links to
  // Glued: the receiver caps of the tile's cells and its one-cell halo in the detail::kW^2
  // scratch layout (0 where no cell), made once when the geometry is loaded: thermal pass 2 reads
  // them in place of a gather every step (a wall's cap is never read: it neither sends nor
  // receives). On a tile by a glued side, each halo cell's source (tile << 10 | index in it,
  // kNoSource where none), so that a step's gather makes no chart look-ups.
  std::unique_ptr<double[]> capHalo;
  std::vector<std::uint32_t> haloSource;
  // Glued, a tile away from the glued sides (not SandField::gluedBorderTile): thermal erosion's
  // planes (kThermal* below), made on the tile's first thermal step.
  std::unique_ptr<double[]> thermalPlanes;
  // Glued explicit diffusion (sand_glued_faces.cpp), once facesKnown: bit lv of sharedE set
  // when the L / d and 1 / d planes give each E face between two cells of row lv the same bits
  // from both cells, bit lv of sharedN when they do so for the N faces from row lv to lv + 1.
  bool facesKnown = false;
  std::uint32_t sharedE = 0, sharedN = 0;
  static constexpr std::uint32_t kNoSource = ~std::uint32_t(0);

  void snapshot() {
    double* e = edge.get();
    const int rows[4] = {0, 1, detail::kT - 2, detail::kT - 1};
    for (int k = 0; k < 4; ++k)
      std::copy_n(cur.get() + rows[k] * detail::kT, detail::kT, e + k * detail::kT);
    double* c = e + 4 * detail::kT;
    for (int lv = 0; lv < detail::kT; ++lv) {
      const double* row = cur.get() + lv * detail::kT;
      c[lv] = row[0];
      c[detail::kT + lv] = row[1];
      c[2 * detail::kT + lv] = row[detail::kT - 2];
      c[3 * detail::kT + lv] = row[detail::kT - 1];
    }
  }
  // Value of (lu, lv) from the snapshot; (lu, lv) must lie in the two outer rows or columns.
  double edgeAt(int lu, int lv) const {
    const double* e = edge.get();
    if (lv < 2) return e[lv * detail::kT + lu];
    if (lv >= detail::kT - 2) return e[(lv - detail::kT + 4) * detail::kT + lu];
    const int k = lu < 2 ? lu : lu - detail::kT + 4;
    return e[4 * detail::kT + k * detail::kT + lv];
  }
};

struct SandField::Pole {
  double h = 0.0;
  bool resident = false;
  bool busy = false, marked = false, inP = false, unwritten = false;
  double s = 0.0;  // thermal: outflow scale of this step
};

// Per-row constants of a thermal step, indexed v + 2 (rows -2 .. m + 2).
struct SandField::ThermalTables {
  std::vector<double> tH, eH, tV, eV, tD, eD, cap, hra, invA;
  double tPole[2] = {0, 0}, ePole[2] = {0, 0};
};

// Per-row constants of a diffusion step, indexed v + 2.
struct SandField::DiffusionTables {
  std::vector<double> gH, gV, invH, invV, invA;
  kernels::Repose repose;
  double zetaInv = 0;
};

// The glued charts' lines for the semi-implicit step (sand_semi_implicit_glued.cpp): in
// direction 0 the chains of W/E links, in direction 1 of S/N links, each cell of the chart in at
// most one line per direction (none where it has no link that way), a line closed into a circle
// where the topology is (rows v and m - v of the octahedral chart, the tubes' seams).
struct SandField::GluedLines {
  struct Direction {
    std::vector<std::uint32_t> cells;  // each line's cells in order: tile << 10 | index in it
    std::vector<std::uint8_t> link;    // link k (< 4) from each cell to the next of its line
    std::vector<std::uint32_t> start;  // line l: cells[start[l] .. start[l + 1])
    std::vector<std::uint8_t> cyclic;
    std::vector<std::vector<int>> byRow;  // by grid row (direction 0) or column (1): its lines
    // Each cell's static geometry in line order (Tile::geo's area, and L / d and 1 / d of its
    // link to the next cell): a sub-step reads only the heights scattered.
    std::vector<double> area, ratio, inv;
  };
  Direction dir[2];
  std::size_t bytes() const;
};

// Tile::geo: the 8 links' chords d (+inf where none), the 4 axis links' face over chord L / d
// and 1 / d (0 where none), the cell's area (0 where no cell) and its receiver cap (A / its
// link count), kT^2 each.
inline constexpr int kGeoChord = 0;
inline constexpr int kGeoRatio = 8;
inline constexpr int kGeoInv = 12;
inline constexpr int kGeoArea = 16;
inline constexpr int kGeoCap = 17;
inline constexpr int kGeoPlanes = 18;

// Tile::thermalPlanes, each detail::kW^2 in the scratch layout (the tile at offset 2): the chords
// of the links E, N, NE and NW of every position (+inf where the other end lies beyond the
// scratch; each link once: a cell's W link is its west neighbour's E, S its south neighbour's N,
// SW its south-west neighbour's NE, SE its south-east neighbour's NW), then the area and the
// receiver cap A / 8 of the tile's cells and their ring (0 beyond). 62 KB against the 72 bytes a
// cell that each of the two passes reads from Tile::geo (docs/SAND.md, "Where the octahedral
// chart's time went").
inline constexpr int kThermalE = 0;
inline constexpr int kThermalN = 1;
inline constexpr int kThermalNE = 2;
inline constexpr int kThermalNW = 3;
inline constexpr int kThermalArea = 4;
inline constexpr int kThermalCap = 5;
inline constexpr int kThermalPlanes = 6;

template <class F>
void SandField::forEachCellOf(int t, F&& f) const {
  const int tu = t % tilesU_, tv = t / tilesU_;
  const bool glued = grid_.glued();
  for (int lv = 0; lv < kT; ++lv) {
    const int v = tv * kT + lv;
    if (!grid_.ordinaryRow(v)) continue;
    for (int lu = 0; lu < kT; ++lu) {
      const int u = tu * kT + lu;
      if (u >= cols_) break;
      if (glued && !grid_.isCell(u, v)) continue;  // a twin on the glued border
      f(u, v, std::size_t(lv * kT + lu));
    }
  }
}

}  // namespace ps::sand
