// The sand field on a chart whose sides are glued beyond lat-long's seam (the octahedral chart,
// both mappings; the torus and the cylinder): per-cell geometry instead of per-row tables, a
// one-cell halo read across the folds and seams through the chart's gluing, no poles
// (docs/SAND.md, "The octahedral chart", "The torus and the cylinder").
//
// Each cell is a distinct point at its canonical grid vertex; its 8 links are the grid continued
// across the glued sides (SandGrid::neighbour; a cone point, a side's midpoint, has 4). A link's
// constants (chord, face) are symmetric functions of its two points, and every flux is one
// expression of the two cells' values, so both cells of a link compute it bit for bit alike.
// Thermal erosion runs in two passes over the tiles (the outflow scale s of every cell, then the
// heights), since a cell's s seen across a fold would otherwise be summed in another order.
// No trapping math lets GCC if-convert the per-cell loops (the same IEEE operations; as
// kernels.cpp).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/input_error.hpp"
#include "sand/kernels.hpp"
#include "sand/sand_field_parts.hpp"

namespace ps::sand {

namespace {
constexpr int kNK = 8;
constexpr int kDuG[8] = {-1, 1, 0, 0, -1, 1, -1, 1};
constexpr int kDvG[8] = {0, 0, -1, 1, -1, -1, 1, 1};
constexpr std::size_t kCells = std::size_t(kT) * kT;
static_assert(kernels::kGluedRow == kT);
}  // namespace

void SandField::loadGeometry(Tile& tile, int t) {
  if (tile.geo) return;
  tile.geo = std::make_unique<double[]>(std::size_t(kGeoPlanes) * kCells);
  tile.boundFactor = computeGeometry(t, tile.geo.get());
  loadHalo(tile, t);
  // The tiles its cells link to (other than itself).
  tile.linked.clear();
  const int tu = t % tilesU_, tv = t / tilesU_;
  for (int lv = 0; lv < kT; ++lv) {
    for (int lu = 0; lu < kT; ++lu) {
      const int u = tu * kT + lu, v = tv * kT + lv;
      if (!cellExists(u, v)) continue;
      for (int k = 0; k < kNK; ++k) {
        const core::GridPoint n = grid_.neighbour(u, v, k);
        if (n.u < 0) continue;
        const int tn = tileIndex(n.u / kT, n.v / kT);
        if (tn != t && std::find(tile.linked.begin(), tile.linked.end(), tn) == tile.linked.end())
          tile.linked.push_back(tn);
      }
    }
  }
}

void SandField::loadInnerLinks(Tile& tile, int t) const {
  // No cell of such a tile lies within two of a glued side, so its cells' links reach the grid
  // neighbours of the tile, which all exist.
  const int tu = t % tilesU_, tv = t / tilesU_;
  tile.linked.clear();
  for (int dv = -1; dv <= 1; ++dv) {
    for (int du = -1; du <= 1; ++du) {
      if (du != 0 || dv != 0) tile.linked.push_back(tileIndex(tu + du, tv + dv));
    }
  }
}

void SandField::loadGeometryEverywhere() {
  geometryEverywhere_ = true;
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    if (tiles_[t] && !tiles_[t]->geo) loadGeometry(*tiles_[t], int(t));
  }
}

double SandField::computeGeometry(int t, double* geo) const {
  const int tu = t % tilesU_, tv = t / tilesU_;
  const double inf = std::numeric_limits<double>::infinity();
  const core::Chart& chart = grid_.chart();
  const core::GridSize& g = grid_.grid();
  // The points of grid positions -1 .. kT from the tile's first vertex, the grid continued
  // across the glued sides (each at its canonical vertex, with its grid index), and the centres
  // of the quads with lower-left corners -1 .. kT - 1: what SandGrid::chord and face compute, from
  // the same points in the same order, so the same bits, once per tile.
  constexpr int kP = kT + 2, kQ = kT + 1;
  const int u0 = tu * kT - 1, v0 = tv * kT - 1;
  std::vector<Eigen::Vector3d> pts(std::size_t(kP) * kP);
  std::vector<std::size_t> idx(std::size_t(kP) * kP, std::size_t(-1));
  for (int b = 0; b < kP; ++b) {
    for (int a = 0; a < kP; ++a) {
      const int u = u0 + a, v = v0 + b;
      if (u < -1 || u > m_ + 1 || v < -1 || v > m_ + 1) continue;
      const core::GridPoint p = chart.continued(u, v);
      const core::GridPoint c = chart.canonical(p.u, p.v);
      pts[std::size_t(b * kP + a)] = grid_.point(c.u, c.v);
      idx[std::size_t(b * kP + a)] = g.index(c.u, c.v);
    }
  }
  std::vector<Eigen::Vector3d> centres(std::size_t(kQ) * kQ);
  for (int b = 0; b < kQ; ++b) {
    for (int a = 0; a < kQ; ++a) {
      std::pair<std::size_t, int> corner[4] = {
          {idx[std::size_t(b * kP + a)], b * kP + a},
          {idx[std::size_t(b * kP + a + 1)], b * kP + a + 1},
          {idx[std::size_t((b + 1) * kP + a + 1)], (b + 1) * kP + a + 1},
          {idx[std::size_t((b + 1) * kP + a)], (b + 1) * kP + a}};
      if (corner[0].first == std::size_t(-1) || corner[1].first == std::size_t(-1) ||
          corner[2].first == std::size_t(-1) || corner[3].first == std::size_t(-1))
        continue;
      std::sort(corner, corner + 4);
      const Eigen::Vector3d sorted[4] = {
          pts[std::size_t(corner[0].second)], pts[std::size_t(corner[1].second)],
          pts[std::size_t(corner[2].second)], pts[std::size_t(corner[3].second)]};
      centres[std::size_t(b * kQ + a)] = grid_.centreOf(sorted);
    }
  }
  double bound = inf;
  for (int lv = 0; lv < kT; ++lv) {
    for (int lu = 0; lu < kT; ++lu) {
      const int u = tu * kT + lu, v = tv * kT + lv;
      const std::size_t i = std::size_t(lv * kT + lu);
      const bool cell = cellExists(u, v);
      const int a = lu + 1, b = lv + 1;  // the cell in pts
      double ratios = 0.0;
      for (int k = 0; k < kNK; ++k) {
        const bool link = cell && grid_.neighbour(u, v, k).u >= 0;
        const double d =
            link ? SandGrid::chordBetween(pts[std::size_t(b * kP + a)],
                                          pts[std::size_t((b + kDvG[k]) * kP + a + kDuG[k])])
                 : inf;
        geo[std::size_t(kGeoChord + k) * kCells + i] = d;
        if (k < 4) {
          // The quads beside the link (SandGrid::face): corners {p, p + d, p + n, p + d + n}
          // and the same with -n, n the link's normal.
          const int du = kDuG[k], dv = kDvG[k], nu = -dv, nv = du;
          auto quad = [&](int su, int sv) -> const Eigen::Vector3d& {
            const int qa = a + std::min({0, du, su, du + su}),
                      qb = b + std::min({0, dv, sv, dv + sv});
            return centres[std::size_t(qb * kQ + qa)];
          };
          const double L = link ? SandGrid::chordBetween(quad(nu, nv), quad(-nu, -nv)) : 0.0;
          const double ratio = link ? L / d : 0.0;
          geo[std::size_t(kGeoRatio + k) * kCells + i] = ratio;
          geo[std::size_t(kGeoInv + k) * kCells + i] = link ? 1.0 / d : 0.0;
          ratios += ratio;
        }
      }
      const double A = cell ? grid_.cellArea(u, v) : 0.0;
      geo[std::size_t(kGeoArea) * kCells + i] = A;
      geo[std::size_t(kGeoCap) * kCells + i] = A * (grid_.linkCount(u, v) == 4 ? 0.25 : 0.125);
      if (cell && ratios > 0.0) bound = std::min(bound, A / ratios);
    }
  }
  return bound;
}

bool SandField::gluedBorderTile(int tu, int tv) const {
  return tu == 0 || tv == 0 || (tu + 1) * kT >= m_ || (tv + 1) * kT >= m_;
}

bool SandField::gluedSource(int tu, int tv, int r, int c, int& tile, int& local) const {
  int u = tu * kT + c - 2, v = tv * kT + r - 2;
  if (u < -1 || u > m_ + 1 || v < -1 || v > m_ + 1) return false;
  // Beyond the cylinder's rims: no cell (a wall; SandGrid::neighbour gives those links none).
  if ((v < 0 || v > m_) && grid_.chart().gluing().vSides == core::SideGluing::kOpen) return false;
  if (u <= 0 || u >= m_ || v <= 0 || v >= m_) {
    const core::Chart& chart = grid_.chart();
    const core::GridPoint p = chart.continued(u, v);
    const core::GridPoint q = chart.canonical(p.u, p.v);
    u = q.u, v = q.v;
  }
  tile = tileIndex(u / kT, v / kT);
  local = (v % kT) * kT + (u % kT);
  return true;
}

// The tile's static halo (Tile::capHalo, Tile::haloSource): each cap is computed as
// computeGeometry computes the source cell's, so it holds the same bits as that cell's plane.
void SandField::loadHalo(Tile& tile, int t) const {
  const int tu = t % tilesU_, tv = t / tilesU_;
  const bool border = gluedBorderTile(tu, tv);
  tile.capHalo = std::make_unique<double[]>(std::size_t(kW) * kW);
  std::fill_n(tile.capHalo.get(), kW * kW, 0.0);
  if (border) tile.haloSource.assign(std::size_t(kW) * kW, Tile::kNoSource);
  for (int r = 1; r < kW - 1; ++r) {
    for (int c = 1; c < kW - 1; ++c) {
      int src = 0, local = 0;
      if (!gluedSource(tu, tv, r, c, src, local)) continue;
      const int u = (src % tilesU_) * kT + local % kT, v = (src / tilesU_) * kT + local / kT;
      const std::size_t at = std::size_t(r * kW + c);
      if (cellExists(u, v))
        tile.capHalo[at] = grid_.cellArea(u, v) * (grid_.linkCount(u, v) == 4 ? 0.25 : 0.125);
      if (border) tile.haloSource[at] = (std::uint32_t(src) << 10) | std::uint32_t(local);
    }
  }
}

// The tile's heights (hs) and thermal outflow scales (ss, optional) with a one-cell halo, in the
// kW x kW scratch layout (the tile at offset 2): cells outside P read as walls (kWall, s = 0).
void SandField::gatherGlued(int tu, int tv, double* hs, double* ss) const {
  const int own = tileIndex(tu, tv);
  if (!gluedBorderTile(tu, tv)) {
    // Inside the grid: no twin within the halo, the lat-long gather's row copies (a two-cell
    // halo, of which the kernels read one), then s from the neighbours' arrays.
    gather(tu, tv, hs);
    if (!ss) return;
    for (int r = 1; r < kW - 1; ++r) {
      const int v = tv * kT + r - 2, tvr = v / kT, lv = v % kT;
      double* srow = ss + r * kW;
      for (int piece = 0; piece < 3; ++piece) {
        const int tn = tileIndex(tu - 1 + piece, tvr);
        const int c0 = piece == 0 ? 1 : (piece == 1 ? 2 : kT + 2);
        const int n = piece == 1 ? kT : 1;
        const int lu0 = piece == 0 ? kT - 1 : 0;
        const Tile* src = inP_[std::size_t(tn)] ? tiles_[std::size_t(tn)].get() : nullptr;
        if (src)
          std::copy_n(src->s.get() + lv * kT + lu0, n, srow + c0);
        else
          std::fill_n(srow + c0, n, 0.0);
      }
    }
    return;
  }
  std::fill_n(hs, kW * kW, kWall);
  if (ss) std::fill_n(ss, kW * kW, 0.0);
  const std::uint32_t* source = tiles_[std::size_t(own)]->haloSource.data();
  for (int r = 1; r < kW - 1; ++r) {
    for (int c = 1; c < kW - 1; ++c) {
      const std::size_t at = std::size_t(r * kW + c);
      const std::uint32_t from = source[at];
      if (from == Tile::kNoSource) continue;
      const int tile = int(from >> 10), local = int(from & 1023u);
      if (!inP_[std::size_t(tile)]) continue;
      const Tile& src = *tiles_[std::size_t(tile)];
      hs[at] = tile == own ? src.cur[std::size_t(local)] : src.edgeAt(local % kT, local / kT);
      if (ss) ss[at] = src.s[std::size_t(local)];
    }
  }
}

double SandField::gluedTileBound(int t) const {
  if (const Tile* tile = tiles_[std::size_t(t)].get(); tile && tile->geo) return tile->boundFactor;
  std::vector<double> geo(std::size_t(kGeoPlanes) * kCells);  // a tile not loaded: computed
  return computeGeometry(t, geo.data());
}

double SandField::gluedBound(const Material& material, bool wholeGrid, bool visited) const {
  const double D = material.diffusion;
  if (!(D > 0.0)) return std::numeric_limits<double>::infinity();
  double factor = std::numeric_limits<double>::infinity();
  if (visited) {
    for (int t : tileList_) factor = std::min(factor, gluedTileBound(t));
  } else {
    for (std::size_t t = 0; t < tiles_.size(); ++t) {
      if (wholeGrid || busy_[t] || marked_[t]) factor = std::min(factor, gluedTileBound(int(t)));
    }
  }
  const double l2 = grid_.cellSize() * grid_.cellSize();
  return factor / (D * l2);
}

bool SandField::gluedLinkActive(Predicate pred, int u, int v, int k,
                                const Material& material) const {
  const core::GridPoint n = grid_.neighbour(u, v, k);
  if (n.u < 0) return false;
  // The chord the step uses: the tile's cached one (bit for bit grid_.chord), from Tile::geo or,
  // on a tile that has none (loadInnerLinks), Tile::thermalPlanes, or before the tile's first
  // thermal step, grid_.chord itself.
  const Tile& tile = *tiles_[std::size_t(tileIndex(u / kT, v / kT))];
  double dist;
  if (tile.geo) {
    dist = tile.geo[std::size_t(kGeoChord + k) * kCells + std::size_t((v % kT) * kT + u % kT)];
  } else if (tile.thermalPlanes) {
    // Link k of the scratch position `at` in the planes (thermalGluedInner's row()).
    constexpr std::size_t kP = std::size_t(kW) * kW;
    constexpr int kPlane[8] = {kThermalE,  kThermalE,  kThermalN,  kThermalN,
                               kThermalNE, kThermalNW, kThermalNW, kThermalNE};
    constexpr int kOffset[8] = {-1, 0, -kW, 0, -kW - 1, -kW + 1, 0, 0};
    const int at = (v % kT + 2) * kW + (u % kT + 2) + kOffset[k];
    dist = tile.thermalPlanes[std::size_t(kPlane[k]) * kP + std::size_t(at)];
  } else {
    dist = grid_.chord(u, v, k);
  }
  const double d = value(u, v) - value(n.u, n.v);
  if (pred == Predicate::kThermal) {
    const double T = material.tanTalus();
    return std::abs(d) - (T * dist + material.cohesion) > material.talusTolerance * T * dist;
  }
  return kernels::weight(std::abs(d), 1.0 / dist, kernels::Repose::of(material)) > 0.0;
}

// The links of tile t's cells to cells of tiles outside P; an active one pulls that tile in.
// Border tiles check every cell (a cell beside a fold links to tiles across the grid), the
// others their outer rows and columns.
void SandField::gluedActiveSetLinks(int t, Predicate pred, const Material& material,
                                    const std::function<void(int)>& add) {
  const int tu = t % tilesU_, tv = t / tilesU_;
  const bool border = gluedBorderTile(tu, tv);
  const int nDirs = pred == Predicate::kThermal ? 8 : 4;
  // Quick exit: every tile its cells link to is in P already.
  const Tile& tile = *tiles_[std::size_t(t)];
  if (std::all_of(tile.linked.begin(), tile.linked.end(),
                  [&](int tn) { return inP_[std::size_t(tn)] != 0; })) {
    return;
  }
  for (int lv = 0; lv < kT; ++lv) {
    const bool edgeRow = border || lv == 0 || lv == kT - 1;
    for (int lu = 0; lu < kT; lu += (edgeRow ? 1 : kT - 1)) {
      const int u = tu * kT + lu, v = tv * kT + lv;
      if (!cellExists(u, v)) continue;
      for (int k = 0; k < nDirs; ++k) {
        const core::GridPoint n = grid_.neighbour(u, v, k);
        if (n.u < 0) continue;
        const int tn = tileIndex(n.u / kT, n.v / kT);
        if (tn == t || inP_[std::size_t(tn)]) continue;
        if (gluedLinkActive(pred, u, v, k, material)) add(tn);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Thermal erosion (the same rule as sand_thermal.cpp's kernels, per cell)

// The per-cell loops run along a tile's rows without branches (cells that are none, twins or
// beyond the grid, are computed and then left as they were), so the compiler vectorises them.
// A tile row's per-cell constants (kernels::GluedRow).
namespace {
kernels::GluedRow rowOf(const double* geo, int lv) {
  const std::size_t row = std::size_t(lv * kT);
  kernels::GluedRow g{};
  for (int k = 0; k < 8; ++k) g.d[k] = geo + std::size_t(kGeoChord + k) * kCells + row;
  for (int k = 0; k < 4; ++k) {
    g.ratio[k] = geo + std::size_t(kGeoRatio + k) * kCells + row;
    g.inv[k] = geo + std::size_t(kGeoInv + k) * kCells + row;
  }
  g.area = geo + std::size_t(kGeoArea) * kCells + row;
  return g;
}
}  // namespace

// The per-cell loops (kernels.cpp, cloned for AVX2 like lat-long's rows) run along a tile's rows
// without branches: cells that are none (twins, positions beyond the grid) are computed and then
// left as they were.
void SandField::thermalGluedPass1(int t, const Material& material, double* hs) {
  const int tu = t % tilesU_, tv = t / tilesU_;
  gatherGlued(tu, tv, hs, nullptr);
  Tile& tile = *tiles_[std::size_t(t)];
  if (!tile.s) tile.s = std::make_unique<double[]>(kCells);
  const double* geo = tile.geo.get();
  for (int lv = 0; lv < kT; ++lv) {
    const double* h0 = hs + (lv + 2) * kW + 2;
    kernels::gluedThermalPass1(h0 - kW, h0, h0 + kW, tile.s.get() + lv * kT, rowOf(geo, lv),
                               material.tanTalus(), material.cohesion, material.talusTolerance,
                               0.5 * material.erosionRate);
  }
}

void SandField::thermalGluedPass2(int t, const Material& material, double* hs, double* ss,
                                  std::uint8_t& busy) {
  const int tu = t % tilesU_, tv = t / tilesU_;
  gatherGlued(tu, tv, hs, ss);
  Tile& tile = *tiles_[std::size_t(t)];
  const double* cs = tile.capHalo.get();
  const double* geo = tile.geo.get();
  // Busy: some cell of the tile or of its halo sends (every halo cell is linked to the tile).
  unsigned any = 0;
  for (int r = 1; r < kW - 1; ++r) {
    for (int c = 1; c < kW - 1; ++c) any |= unsigned(ss[r * kW + c] > 0.0);
  }
  for (int lv = 0; lv < kT; ++lv) {
    const int at = (lv + 2) * kW + 2;
    kernels::gluedThermalPass2(hs + at - kW, hs + at, hs + at + kW, ss + at - kW, ss + at,
                               ss + at + kW, cs + at - kW, cs + at, cs + at + kW,
                               tile.cur.get() + lv * kT, rowOf(geo, lv), material.tanTalus(),
                               material.cohesion, material.talusTolerance);
  }
  busy = any ? 1 : 0;
}

// Each link's chord once (Tile::thermalPlanes), from the same points in the same order as
// computeGeometry's: SandGrid::chordBetween gives (a, b) and (b, a) the same bits, and no twin,
// fold or cone point lies within two cells of such a tile, so the same bits as Tile::geo's.
void SandField::loadThermalPlanes(Tile& tile, int t) const {
  const int u0 = (t % tilesU_) * kT - 2, v0 = (t / tilesU_) * kT - 2;
  constexpr std::size_t kP = std::size_t(kW) * kW;
  std::vector<Eigen::Vector3d> pts(kP);
  for (int r = 0; r < kW; ++r) {
    for (int c = 0; c < kW; ++c) pts[std::size_t(r * kW + c)] = grid_.point(u0 + c, v0 + r);
  }
  tile.thermalPlanes = std::make_unique<double[]>(kThermalPlanes * kP);
  double* planes = tile.thermalPlanes.get();
  std::fill_n(planes, kThermalArea * kP, std::numeric_limits<double>::infinity());
  std::fill_n(planes + kThermalArea * kP, (kThermalPlanes - kThermalArea) * kP, 0.0);
  constexpr int kDu[4] = {1, 0, 1, -1}, kDv[4] = {0, 1, 1, 1};  // E N NE NW
  for (int k = 0; k < 4; ++k) {
    for (int r = 0; r + kDv[k] < kW; ++r) {
      for (int c = std::max(0, -kDu[k]); c < kW && c + kDu[k] < kW; ++c) {
        planes[std::size_t(k) * kP + std::size_t(r * kW + c)] = SandGrid::chordBetween(
            pts[std::size_t(r * kW + c)], pts[std::size_t((r + kDv[k]) * kW + c + kDu[k])]);
      }
    }
  }
  for (int r = 1; r < kW - 1; ++r) {
    for (int c = 1; c < kW - 1; ++c) {
      const double A = grid_.cellArea(u0 + c, v0 + r);
      planes[kThermalArea * kP + std::size_t(r * kW + c)] = A;
      planes[kThermalCap * kP + std::size_t(r * kW + c)] = A * 0.125;  // computeGeometry's cap
    }
  }
}

void SandField::thermalGluedInner(int t, const Material& material, double* hs, double* ss,
                                  std::uint8_t& busy) {
  gather(t % tilesU_, t / tilesU_, hs);  // a two-cell halo, walls outside P
  Tile& tile = *tiles_[std::size_t(t)];
  if (!tile.thermalPlanes) loadThermalPlanes(tile, t);
  if (!tile.s) tile.s = std::make_unique<double[]>(kCells);
  constexpr std::size_t kP = std::size_t(kW) * kW;
  const double* planes = tile.thermalPlanes.get();
  const double* pE = planes + kThermalE * kP;
  const double* pN = planes + kThermalN * kP;
  const double* pNE = planes + kThermalNE * kP;
  const double* pNW = planes + kThermalNW * kP;
  const double* cap = planes + kThermalCap * kP;
  // The chords of the 8 links of the cells from scratch position `at` on (W E S N SW SE NW NE).
  auto row = [&](int at) {
    kernels::GluedRow g{};
    g.d[0] = pE + at - 1, g.d[1] = pE + at, g.d[2] = pN + at - kW, g.d[3] = pN + at;
    g.d[4] = pNE + at - kW - 1, g.d[5] = pNW + at - kW + 1, g.d[6] = pNW + at, g.d[7] = pNE + at;
    g.area = planes + kThermalArea * kP + at;
    return g;
  };
  const double T = material.tanTalus(), coh = material.cohesion, eta = material.talusTolerance;
  // s of the tile's cells and their ring (scratch rows and columns 1 .. kW - 2).
  for (int r = 1; r < kW - 1; ++r) {
    const int at = r * kW + 1;
    kernels::gluedThermalPass1(hs + at - kW, hs + at, hs + at + kW, ss + at, row(at), T, coh, eta,
                               0.5 * material.erosionRate, kW - 2);
  }
  // Busy: some cell of the tile or of its ring sends (as thermalGluedPass2).
  unsigned any = 0;
  for (int r = 1; r < kW - 1; ++r) {
    for (int c = 1; c < kW - 1; ++c) any |= unsigned(ss[r * kW + c] > 0.0);
  }
  // The tile's own s, for the border tiles' pass 2 after the barrier.
  for (int lv = 0; lv < kT; ++lv) std::copy_n(ss + (lv + 2) * kW + 2, kT, tile.s.get() + lv * kT);
  for (int lv = 0; lv < kT; ++lv) {
    const int at = (lv + 2) * kW + 2;
    kernels::gluedThermalPass2(hs + at - kW, hs + at, hs + at + kW, ss + at - kW, ss + at,
                               ss + at + kW, cap + at - kW, cap + at, cap + at + kW,
                               tile.cur.get() + lv * kT, row(at), T, coh, eta);
  }
  busy = any ? 1 : 0;
}

StepReport SandField::thermalStepGlued(const Material& material) {
  StepReport rep;
  if (atRest()) return rep;
  buildActiveSet(Predicate::kThermal, material);
  std::vector<std::uint8_t> busyOut(tileList_.size(), 0);
  const int n = int(tileList_.size());
#pragma omp parallel if (n >= kParallelTiles)
  {
    std::vector<double> hs(std::size_t(kW) * kW), ss(std::size_t(kW) * kW);
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) tiles_[std::size_t(tileList_[std::size_t(j)])]->snapshot();
      // (barrier: every tile's edge holds the heights before the step)
      // The tiles away from the glued sides step in one pass; the others store their s, then
      // (after the barrier, every cell's s known) step.
#pragma omp for schedule(dynamic, 1)
    for (int j = 0; j < n; ++j) {
      const int t = tileList_[std::size_t(j)];
      if (gluedBorderTile(t % tilesU_, t / tilesU_)) {
        thermalGluedPass1(t, material, hs.data());
      } else {
        thermalGluedInner(t, material, hs.data(), ss.data(), busyOut[std::size_t(j)]);
      }
    }
#pragma omp for schedule(dynamic, 1)
    for (int j = 0; j < n; ++j) {
      const int t = tileList_[std::size_t(j)];
      if (gluedBorderTile(t % tilesU_, t / tilesU_))
        thermalGluedPass2(t, material, hs.data(), ss.data(), busyOut[std::size_t(j)]);
    }
  }
  for (int j = 0; j < n; ++j)
    busy_[std::size_t(tileList_[std::size_t(j)])] = busyOut[std::size_t(j)];
  finishStep(rep);
  return rep;
}

// ---------------------------------------------------------------------------------------------
// Explicit drift-diffusion (kernels::diffusionRow's rule, per cell)

void SandField::diffusionGluedTile(int t, const DiffusionTables& tb, double dt,
                                   const PushForce* force, double* hs, std::uint8_t& busy) {
  const int tu = t % tilesU_, tv = t / tilesU_;
  gatherGlued(tu, tv, hs, nullptr);
  Tile& tile = *tiles_[std::size_t(t)];
  const double* geo = tile.geo.get();
  const double Dl2 = diffusionMaterial_.diffusion * grid_.cellSize() * grid_.cellSize();
  // Each face weighed once where both its cells see it alike (sand_glued_faces.cpp); a tile
  // where no row's do keeps the row kernel. The force's drift below reads no heights, so it
  // may follow the rows.
  const bool shared = gluedFacesShared(tile);
  unsigned any = shared ? diffusionGluedFaces(tile, hs, tb, Dl2, dt) : 0;
  for (int lv = 0; lv < kT; ++lv) {
    const double* h0 = hs + (lv + 2) * kW + 2;
    double* out = tile.cur.get() + lv * kT;
    const kernels::GluedRow g = rowOf(geo, lv);
    if (!shared)
      any |= kernels::gluedDiffusionRow(h0 - kW, h0, h0 + kW, out, g, Dl2, dt, tb.repose);
    if (force) {
      for (int c = 0; c < kT; ++c) {
        const double A = g.area[c];
        if (!(A > 0.0)) continue;
        const double fd = netDriftFluxGlued(*force, tb.zetaInv, tu * kT + c, tv * kT + lv);
        if (fd != 0.0) {
          out[c] -= dt * fd * (1.0 / A);
          any = 1;
        }
      }
    }
  }
  busy = any ? 1 : 0;
}

// The force's drift out of cell (u, v) through its axis faces; each face's flux from the
// endpoint with the smaller grid index, so both cells get it bit for bit.
double SandField::netDriftFluxGlued(const PushForce& force, double zetaInv, int u, int v) const {
  const core::GridSize& g = grid_.grid();
  double f = 0.0;
  for (int k = 0; k < 4; ++k) {
    const core::GridPoint n = grid_.neighbour(u, v, k);
    if (n.u < 0) continue;
    const bool swap = g.index(n.u, n.v) < g.index(u, v);
    const Eigen::Vector3d a = grid_.point(u, v), b = grid_.point(n.u, n.v);
    const double L = grid_.face(u, v, k);
    const double flux =
        swap ? driftBetween(force, zetaInv, b, a, L) : driftBetween(force, zetaInv, a, b, L);
    f += swap ? -flux : flux;
  }
  return f;
}

}  // namespace ps::sand
