#include "sand/sand_field.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <numbers>

#include "core/input_error.hpp"
#include "sand/kernels.hpp"

namespace ps::sand {

namespace {

constexpr int kT = SandField::kTile;
constexpr int kW = kernels::kScratch;  // scratch row stride: the tile and 2 cells each side
static_assert(kW == kT + 4);
constexpr double kWall = kernels::kWall;
constexpr double kNever = 1e300;  // threshold of a link that does not exist
// Steps over fewer tiles run on one thread: a fork/join costs more than a few tiles of work
// (milliseconds when the cores are shared and a waiting thread is descheduled).
constexpr int kParallelTiles = 64;

}  // namespace

// A tile's heights are updated in place; before a step writes any tile, every tile of the step
// copies its two outermost rows and columns (`edge`), and neighbours read their halo from there.
// `next` exists only for the semi-implicit step (allocated on first use).
struct SandField::Tile {
  std::unique_ptr<double[]> cur, next;
  // rows 0, 1, kT-2, kT-1 (4 x kT), then columns 0, 1, kT-2, kT-1 (4 x kT, by row)
  std::unique_ptr<double[]> edge;
  bool unwritten = false;  // cur may differ from the floats

  void snapshot() {
    double* e = edge.get();
    const int rows[4] = {0, 1, kT - 2, kT - 1};
    for (int k = 0; k < 4; ++k) std::copy_n(cur.get() + rows[k] * kT, kT, e + k * kT);
    double* c = e + 4 * kT;
    for (int lv = 0; lv < kT; ++lv) {
      const double* row = cur.get() + lv * kT;
      c[lv] = row[0];
      c[kT + lv] = row[1];
      c[2 * kT + lv] = row[kT - 2];
      c[3 * kT + lv] = row[kT - 1];
    }
  }
  // Value of (lu, lv) from the snapshot; (lu, lv) must lie in the two outer rows or columns.
  double edgeAt(int lu, int lv) const {
    const double* e = edge.get();
    if (lv < 2) return e[lv * kT + lu];
    if (lv >= kT - 2) return e[(lv - kT + 4) * kT + lu];
    const int k = lu < 2 ? lu : lu - kT + 4;
    return e[4 * kT + k * kT + lv];
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

SandField::SandField(std::shared_ptr<const core::Chart> chart, std::span<float> heights)
    : grid_(std::move(chart)), heights_(heights) {
  if (heights.size() != grid_.grid().count()) {
    throw core::InputError("sand field: got " + std::to_string(heights.size()) + " heights for a " +
                           grid_.grid().label() + " grid");
  }
  m_ = grid_.m();
  cols_ = grid_.columns();
  tilesU_ = (cols_ + kT - 1) / kT;
  tilesV_ = (m_ + 1 + kT - 1) / kT;
  tiles_.resize(std::size_t(tilesU_) * std::size_t(tilesV_));
  busy_.assign(tiles_.size(), 0);
  marked_.assign(tiles_.size(), 0);
  inP_.assign(tiles_.size(), 0);
  poles_ = std::make_unique<Pole[]>(2);
  if (grid_.sphere()) {
    poleFlux_[0].assign(std::size_t(m_), 0.0);
    poleFlux_[1].assign(std::size_t(m_), 0.0);
  }
}

SandField::~SandField() = default;

bool SandField::cellExists(int u, int v) const {
  return u >= 0 && u < cols_ && grid_.ordinaryRow(v);
}

int SandField::wrapTileU(int tu) const {
  if (tu >= 0 && tu < tilesU_) return tu;
  if (!grid_.sphere()) return -1;
  return (tu % tilesU_ + tilesU_) % tilesU_;
}

SandField::Tile& SandField::loadTile(int t) {
  auto& ptr = tiles_[std::size_t(t)];
  if (ptr) return *ptr;
  ptr = std::make_unique<Tile>();
  ptr->cur = std::make_unique<double[]>(std::size_t(kT) * kT);
  ptr->edge = std::make_unique<double[]>(std::size_t(8) * kT);
  const int tu = t % tilesU_, tv = t / tilesU_;
  const core::GridSize& g = grid_.grid();
  for (int lv = 0; lv < kT; ++lv) {
    const int v = tv * kT + lv;
    for (int lu = 0; lu < kT; ++lu) {
      const int u = tu * kT + lu;
      ptr->cur[std::size_t(lv * kT + lu)] =
          cellExists(u, v) ? double(heights_[g.index(u, v)]) : kWall;
    }
  }
  return *ptr;
}

void SandField::loadPole(int p) {
  Pole& pole = poles_[std::size_t(p)];
  if (pole.resident) return;
  pole.h = double(heights_[grid_.grid().index(0, p == 0 ? 0 : m_)]);
  pole.resident = true;
}

double SandField::value(int u, int v) const {
  const int t = tileIndex(u / kT, v / kT);
  if (const auto& tile = tiles_[std::size_t(t)]) {
    return tile->cur[std::size_t((v % kT) * kT + (u % kT))];
  }
  return double(heights_[grid_.grid().index(u, v)]);
}

double SandField::poleValue(int p) const {
  const Pole& pole = poles_[std::size_t(p)];
  return pole.resident ? pole.h : double(heights_[grid_.grid().index(0, p == 0 ? 0 : m_)]);
}

double SandField::height(int u, int v) const {
  if (u < 0 || u > m_ || v < 0 || v > m_) {
    throw core::InputError("height: vertex (" + std::to_string(u) + ", " + std::to_string(v) +
                           ") is outside the grid");
  }
  if (grid_.sphere()) {
    if (v == 0) return poleValue(0);
    if (v == m_) return poleValue(1);
    if (u == m_) u = 0;
  }
  return value(u, v);
}

void SandField::copyHeights(std::vector<double>& out) const {
  const core::GridSize& g = grid_.grid();
  out.resize(g.count());
  for (int v = 0; v <= m_; ++v) {
    for (int u = 0; u <= m_; ++u) out[g.index(u, v)] = height(u, v);
  }
}

double SandField::volume() const {
  CompensatedSum total;
  for (int v = 0; v <= m_; ++v) {
    CompensatedSum row;
    if (grid_.sphere() && (v == 0 || v == m_)) {
      row.add(poleValue(v == 0 ? 0 : 1));
    } else {
      for (int u = 0; u < cols_; ++u) row.add(value(u, v));
    }
    total.add(grid_.area(v) * row.value());
  }
  return total.value();
}

std::size_t SandField::residentBytes() const {
  std::size_t bytes = 0;
  for (const auto& t : tiles_) {
    if (!t) continue;
    bytes += (std::size_t(kT) * kT * (t->next ? 2 : 1) + std::size_t(8) * kT) * sizeof(double);
  }
  return bytes;
}

std::size_t SandField::residentTiles() const {
  return std::size_t(
      std::count_if(tiles_.begin(), tiles_.end(), [](const auto& t) { return bool(t); }));
}

// ---------------------------------------------------------------------------------------------
// Activity

void SandField::mark(const terrain::GridRegion& region) {
  if (region.empty()) return;
  const core::GridSize& g = grid_.grid();
  const int v0 = std::max(0, region.vBegin), v1 = std::min(m_, region.vEnd);
  if (v0 > v1) return;
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) {
      const int v = p == 0 ? 0 : m_;
      if (v < v0 || v > v1) continue;
      Pole& pole = poles_[std::size_t(p)];
      pole.marked = true;
      const float f = heights_[g.index(0, v)];
      if (pole.resident && static_cast<float>(pole.h) != f) pole.h = double(f);
    }
  }
  region.forEachColumnRange(g, [&](int a, int b) {
    b = std::min(b, cols_ - 1);  // u = m on the sphere is u = 0 (handled below)
    for (int tv = v0 / kT; tv <= v1 / kT; ++tv) {
      for (int tu = a / kT; tu <= b / kT; ++tu) {
        const int t = tileIndex(tu, tv);
        marked_[std::size_t(t)] = 1;
        Tile* tile = tiles_[std::size_t(t)].get();
        if (!tile) continue;
        const int va = std::max(v0, tv * kT), vb = std::min(v1, tv * kT + kT - 1);
        const int ua = std::max(a, tu * kT), ub = std::min(b, tu * kT + kT - 1);
        for (int v = va; v <= vb; ++v) {
          if (!grid_.ordinaryRow(v)) continue;
          for (int u = ua; u <= ub; ++u) {
            double& x = tile->cur[std::size_t((v - tv * kT) * kT + (u - tu * kT))];
            const float f = heights_[g.index(u, v)];
            if (static_cast<float>(x) != f) x = double(f);
          }
        }
      }
    }
  });
  // A change at u = m on the sphere is a change at u = 0.
  if (grid_.sphere()) {
    bool seam = false;
    region.forEachColumnRange(g, [&](int a, int b) { seam |= (b == m_ || a == m_); });
    if (seam) mark(terrain::GridRegion{0, 0, v0, v1});
  }
}

void SandField::markAll() {
  std::fill(marked_.begin(), marked_.end(), std::uint8_t(1));
  if (grid_.sphere()) poles_[0].marked = poles_[1].marked = true;
}

std::size_t SandField::resync() {
  const core::GridSize& g = grid_.grid();
  std::size_t reloaded = 0;
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    Tile* tile = tiles_[t].get();
    if (!tile) continue;
    const int tu = int(t) % tilesU_, tv = int(t) / tilesU_;
    bool any = false;
    for (int lv = 0; lv < kT; ++lv) {
      const int v = tv * kT + lv;
      if (!grid_.ordinaryRow(v)) continue;
      for (int lu = 0; lu < kT; ++lu) {
        const int u = tu * kT + lu;
        if (u >= cols_) break;
        double& x = tile->cur[std::size_t(lv * kT + lu)];
        const float f = heights_[g.index(u, v)];
        if (static_cast<float>(x) != f) {
          x = double(f);
          any = true;
          ++reloaded;
        }
      }
    }
    if (any) marked_[t] = 1;
  }
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (!pole.resident) continue;
      const float f = heights_[g.index(0, p == 0 ? 0 : m_)];
      if (static_cast<float>(pole.h) != f) {
        pole.h = double(f);
        pole.marked = true;
        ++reloaded;
      }
    }
  }
  return reloaded;
}

bool SandField::atRest() const {
  return pendingTiles() == 0;
}

std::size_t SandField::pendingTiles() const {
  std::size_t n = 0;
  for (std::size_t t = 0; t < tiles_.size(); ++t) n += (busy_[t] || marked_[t]) ? 1 : 0;
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) n += (poles_[p].busy || poles_[p].marked) ? 1 : 0;
  }
  return n;
}

bool SandField::linkActive(Predicate pred, int ua, int va, int ub, int vb,
                           const Material& material) const {
  const double d = value(ua, va) - value(ub, vb);
  const int vl = std::min(va, vb);
  double dist;
  bool diagonal = false;
  if (va == vb) {
    dist = grid_.horizontal(va);
  } else if (ua == ub) {
    dist = grid_.vertical(vl);
  } else {
    dist = grid_.diagonal(vl);
    diagonal = true;
  }
  if (pred == Predicate::kThermal) {
    const double T = material.tanTalus();
    return std::abs(d) - (T * dist + material.cohesion) > material.talusTolerance * T * dist;
  }
  if (diagonal) return false;
  const kernels::Repose r = kernels::Repose::of(material);
  return kernels::weight(std::abs(d), 1.0 / dist, r) > 0.0;
}

bool SandField::poleLinkActive(Predicate pred, int p, int u, const Material& material) const {
  const int vr = p == 0 ? 1 : m_ - 1;
  const double d = poleValue(p) - value(u, vr);
  const double dist = grid_.vertical(p == 0 ? 0 : m_ - 1);
  if (pred == Predicate::kThermal) {
    const double T = material.tanTalus();
    return std::abs(d) - (T * dist + material.cohesion) > material.talusTolerance * T * dist;
  }
  return kernels::weight(std::abs(d), 1.0 / dist, kernels::Repose::of(material)) > 0.0;
}

void SandField::buildActiveSet(Predicate pred, const Material& material) {
  tileList_.clear();
  std::vector<int> work;
  auto add = [&](int t) {
    if (inP_[std::size_t(t)]) return;
    inP_[std::size_t(t)] = 1;
    loadTile(t);
    tileList_.push_back(t);
    work.push_back(t);
  };
  const bool sphere = grid_.sphere();
  std::vector<int> poleWork;
  auto addPole = [&](int p) {
    Pole& pole = poles_[std::size_t(p)];
    if (pole.inP) return;
    pole.inP = true;
    loadPole(p);
    poleWork.push_back(p);
  };
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    if (busy_[t] || marked_[t]) add(int(t));
  }
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      if (poles_[p].busy || poles_[p].marked) addPole(p);
    }
  }
  const int nDirs = pred == Predicate::kThermal ? 8 : 4;
  static constexpr int kDu[8] = {-1, 1, 0, 0, -1, 1, -1, 1};
  static constexpr int kDv[8] = {0, 0, -1, 1, -1, -1, 1, 1};
  while (!work.empty() || !poleWork.empty()) {
    if (!work.empty()) {
      const int t = work.back();
      work.pop_back();
      const int tu = t % tilesU_, tv = t / tilesU_;
      // Quick exit: all neighbour tiles already in P (or absent).
      bool open = false;
      for (int dv = -1; dv <= 1 && !open; ++dv) {
        for (int du = -1; du <= 1 && !open; ++du) {
          const int nu = wrapTileU(tu + du), nv = tv + dv;
          if (nu < 0 || nv < 0 || nv >= tilesV_) continue;
          if (!inP_[std::size_t(tileIndex(nu, nv))]) open = true;
        }
      }
      if (open) {
        // Border cells of the tile.
        for (int lv = 0; lv < kT; ++lv) {
          const int v = tv * kT + lv;
          if (!grid_.ordinaryRow(v)) continue;
          const bool edgeRow = (lv == 0 || lv == kT - 1);
          for (int lu = 0; lu < kT; lu += (edgeRow ? 1 : kT - 1)) {
            const int u = tu * kT + lu;
            if (u >= cols_) break;
            for (int k = 0; k < nDirs; ++k) {
              int un = u + kDu[k];
              const int vn = v + kDv[k];
              if (sphere) un = (un + m_) % m_;
              if (!cellExists(un, vn)) continue;
              const int tn = tileIndex(un / kT, vn / kT);
              if (tn == t || inP_[std::size_t(tn)]) continue;
              if (linkActive(pred, u, v, un, vn, material)) add(tn);
            }
          }
        }
      }
      if (sphere) {
        for (int p = 0; p < 2; ++p) {
          const int vr = p == 0 ? 1 : m_ - 1;
          if (poles_[p].inP || vr / kT != tv) continue;
          for (int lu = 0; lu < kT && tu * kT + lu < cols_; ++lu) {
            if (poleLinkActive(pred, p, tu * kT + lu, material)) {
              addPole(p);
              break;
            }
          }
        }
      }
    } else {
      const int p = poleWork.back();
      poleWork.pop_back();
      const int vr = p == 0 ? 1 : m_ - 1;
      for (int u = 0; u < m_; ++u) {
        const int t = tileIndex(u / kT, vr / kT);
        if (inP_[std::size_t(t)]) continue;
        if (poleLinkActive(pred, p, u, material)) add(t);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Gathering a tile and its halo

void SandField::gather(int tu, int tv, double* hs) const {
  const int v0 = tv * kT - 2;
  for (int r = 0; r < kW; ++r) {
    double* row = hs + r * kW;
    const int v = v0 + r;
    if (!grid_.ordinaryRow(v)) {
      double x = kWall;
      if (grid_.sphere() && (v == 0 || v == m_)) {
        const Pole& pole = poles_[v == 0 ? 0 : 1];
        if (pole.inP) x = pole.h;
      }
      std::fill_n(row, kW, x);
      continue;
    }
    const int tvr = v / kT, lv = v % kT;
    auto piece = [&](int c0, int c1, int tuN, int lu0) {
      const int tw = wrapTileU(tuN);
      if (tw < 0 || !inP_[std::size_t(tileIndex(tw, tvr))]) {
        std::fill(row + c0, row + c1, kWall);
        return;
      }
      const Tile& src = *tiles_[std::size_t(tileIndex(tw, tvr))];
      const int valid = std::max(0, std::min(c1 - c0, cols_ - (tw * kT + lu0)));
      if (tw == tu && tvr == tv) {  // own heights (not yet written this step)
        std::copy_n(src.cur.get() + lv * kT + lu0, valid, row + c0);
      } else if (lv < 2 || lv >= kT - 2) {  // one of the neighbour's two outer rows
        std::copy_n(src.edge.get() + (lv < 2 ? lv : lv - kT + 4) * kT + lu0, valid, row + c0);
      } else {
        for (int c = c0; c < c0 + valid; ++c) row[c] = src.edgeAt(lu0 + (c - c0), lv);
      }
      std::fill(row + c0 + valid, row + c1, kWall);
    };
    piece(0, 2, tu - 1, kT - 2);
    piece(2, kT + 2, tu, 0);
    piece(kT + 2, kT + 4, tu + 1, 0);
  }
}

// ---------------------------------------------------------------------------------------------
// Thermal erosion

void SandField::thermalTile(int tu, int tv, const ThermalTables& tb, double* hs, double* ss,
                            std::uint8_t& busy) {
  gather(tu, tv, hs);
  const int v0 = tv * kT - 2;
  const bool sphere = grid_.sphere();
  unsigned any = 0;
  // Pass 1: outflow scale s of the tile and its first ring.
  std::fill_n(ss, kW, 0.0);
  std::fill_n(ss + (kW - 1) * kW, kW, 0.0);
  for (int r = 1; r < kW - 1; ++r) {
    double* s = ss + r * kW;
    const int v = v0 + r;
    s[0] = s[kW - 1] = 0.0;
    if (!grid_.ordinaryRow(v)) {
      double x = 0.0;
      if (sphere && (v == 0 || v == m_)) {
        const Pole& pole = poles_[v == 0 ? 0 : 1];
        if (pole.inP) x = pole.s;
      }
      std::fill_n(s, kW, x);
      continue;
    }
    const std::size_t i = std::size_t(v + 2);
    const kernels::ThermalRow1 k{tb.tH[i], tb.eH[i], tb.tV[i - 1], tb.eV[i - 1],
                                 tb.tV[i], tb.eV[i], tb.tD[i - 1], tb.eD[i - 1],
                                 tb.tD[i], tb.eD[i], tb.hra[i]};
    any |= kernels::thermalPass1(hs + (r - 1) * kW, hs + r * kW, hs + (r + 1) * kW, s, k);
  }
  // A pole that sends reaches the tile's ring cells.
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      const int vr = p == 0 ? 1 : m_ - 1;
      if (vr / kT == tv && poles_[p].inP && poles_[p].s > 0.0) any = 1;
    }
  }
  // Pass 2: new heights of the tile's own cells.
  Tile& tile = *tiles_[std::size_t(tileIndex(tu, tv))];
  for (int lv = 0; lv < kT; ++lv) {
    const int r = lv + 2, v = v0 + r;
    double* out = tile.cur.get() + lv * kT - 2;  // in place: the scratch holds the old values
    if (!grid_.ordinaryRow(v)) {
      std::fill_n(out + 2, kT, kWall);
      continue;
    }
    const std::size_t i = std::size_t(v + 2);
    const kernels::ThermalRow2 k{tb.tH[i],  tb.eH[i],      tb.tV[i - 1],  tb.eV[i - 1], tb.tV[i],
                                 tb.eV[i],  tb.tD[i - 1],  tb.eD[i - 1],  tb.tD[i],     tb.eD[i],
                                 tb.cap[i], tb.cap[i - 1], tb.cap[i + 1], tb.invA[i]};
    const double* hm = hs + (r - 1) * kW;
    const double* h0 = hs + r * kW;
    const double* hp = hs + (r + 1) * kW;
    const double* sm = ss + (r - 1) * kW;
    const double* s0 = ss + r * kW;
    const double* sp = ss + (r + 1) * kW;
    kernels::thermalPass2(hm, h0, hp, sm, s0, sp, out, k);
    // Ring rows: the flux each ring cell exchanged with its pole, recomputed with the kernel's
    // own formula (bit for bit the term it added).
    if (sphere && (v == 1 || v == m_ - 1)) {
      const int p = v == 1 ? 0 : 1;
      const double* hq = p == 0 ? hm : hp;  // the pole row of the scratch
      const double* sq = p == 0 ? sm : sp;
      const double t = p == 0 ? k.tS : k.tN, e = p == 0 ? k.eS : k.eN;
      const double capP = p == 0 ? k.capS : k.capN;
      for (int c = 2; c < kT + 2; ++c) {
        const int u = tu * kT + c - 2;
        if (u >= cols_) break;
        const double d = h0[c] - hq[c];
        const double n = std::min(sq[c], k.cap0) * kernels::act(-d - t, e) -
                         std::min(s0[c], capP) * kernels::act(d - t, e);
        poleFlux_[p][std::size_t(u)] = -n;
      }
    }
  }
  busy = any ? 1 : 0;
}

const SandField::ThermalTables& SandField::thermalTables(const Material& material) {
  if (thermalTables_ && thermalMaterial_ == material) return *thermalTables_;
  auto tables = std::make_unique<ThermalTables>();
  ThermalTables& tb = *tables;
  const bool sphere = grid_.sphere();
  const std::size_t rows = std::size_t(m_) + 5;
  for (auto* a : {&tb.tH, &tb.eH, &tb.tV, &tb.eV, &tb.tD, &tb.eD, &tb.cap, &tb.hra, &tb.invA})
    a->assign(rows, 0.0);
  const double T = material.tanTalus(), coh = material.cohesion, eta = material.talusTolerance;
  const double halfRate = 0.5 * material.erosionRate;
  for (int v = 0; v <= m_; ++v) {
    const std::size_t i = std::size_t(v + 2);
    const double A = grid_.area(v);
    if (grid_.ordinaryRow(v)) {
      tb.tH[i] = T * grid_.horizontal(v) + coh;
      tb.eH[i] = eta * T * grid_.horizontal(v);
      tb.cap[i] = A / 8.0;
    } else if (sphere) {
      tb.cap[i] = A / double(m_);  // a pole receives from its m ring cells
    }
    tb.hra[i] = halfRate * A;
    tb.invA[i] = 1.0 / A;
    if (v < m_) {
      const bool both = grid_.ordinaryRow(v) && grid_.ordinaryRow(v + 1);
      const bool poleLink = sphere && (v == 0 || v == m_ - 1);
      if (both || poleLink) {
        tb.tV[i] = T * grid_.vertical(v) + coh;
        tb.eV[i] = eta * T * grid_.vertical(v);
      }
      if (both) {
        tb.tD[i] = T * grid_.diagonal(v) + coh;
        tb.eD[i] = eta * T * grid_.diagonal(v);
      } else {
        tb.tD[i] = kNever;  // a pole is one neighbour, reached by the vertical link only
      }
    }
  }
  thermalTables_ = std::move(tables);
  thermalMaterial_ = material;
  return *thermalTables_;
}

StepReport SandField::thermalStep(const Material& material) {
  material.validate();
  StepReport rep;
  if (atRest()) return rep;
  buildActiveSet(Predicate::kThermal, material);
  const bool sphere = grid_.sphere();
  const ThermalTables& tb = thermalTables(material);
  // Poles, pass 1 (before the tiles, which read s).
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      pole.s = 0.0;
      if (!pole.inP) continue;
      const int vr = p == 0 ? 1 : m_ - 1;
      const std::size_t i = std::size_t((p == 0 ? 0 : m_ - 1) + 2);
      double E = 0.0, mx = 0.0;
      for (int u = 0; u < m_; ++u) {
        if (!inP_[std::size_t(tileIndex(u / kT, vr / kT))]) continue;
        const double e = kernels::act(pole.h - value(u, vr) - tb.tV[i], tb.eV[i]);
        E += e;
        mx = std::max(mx, e);
      }
      pole.s = E > 0.0 ? tb.hra[std::size_t((p == 0 ? 0 : m_) + 2)] * mx / E : 0.0;
      std::fill(poleFlux_[p].begin(), poleFlux_[p].end(), 0.0);
    }
  }
  std::vector<std::uint8_t> busyOut(tileList_.size(), 0);
  const int n = int(tileList_.size());
#pragma omp parallel if (n >= kParallelTiles)
  {
    std::vector<double> hs(std::size_t(kW) * kW), ss(std::size_t(kW) * kW);
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) tiles_[std::size_t(tileList_[std::size_t(j)])]->snapshot();
      // (barrier: every tile's edge holds the heights before the step)
#pragma omp for schedule(dynamic, 1)
    for (int j = 0; j < n; ++j) {
      const int t = tileList_[std::size_t(j)];
      thermalTile(t % tilesU_, t / tilesU_, tb, hs.data(), ss.data(), busyOut[std::size_t(j)]);
    }
  }
  for (int j = 0; j < n; ++j)
    busy_[std::size_t(tileList_[std::size_t(j)])] = busyOut[std::size_t(j)];
  // Poles, pass 2.
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (!pole.inP) continue;
      double in = 0.0;
      bool moved = pole.s > 0.0;
      for (double f : poleFlux_[p]) {
        in += f;
        moved |= f != 0.0;
      }
      pole.h += in * (1.0 / grid_.area(p == 0 ? 0 : m_));
      pole.busy = moved;
    }
  }
  finishStep(rep);
  return rep;
}

void SandField::finishStep(StepReport& rep) {
  for (int t : tileList_) {
    Tile& tile = *tiles_[std::size_t(t)];
    const int tu = t % tilesU_, tv = t / tilesU_;
    const int w = std::min(kT, cols_ - tu * kT);
    int h = 0;
    for (int lv = 0; lv < kT; ++lv) h += grid_.ordinaryRow(tv * kT + lv) ? 1 : 0;
    rep.cells += std::size_t(w) * std::size_t(h);
    if (busy_[std::size_t(t)]) {
      tile.unwritten = true;
      rep.moved = true;
    }
    marked_[std::size_t(t)] = 0;
    inP_[std::size_t(t)] = 0;
  }
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (pole.inP) {
        rep.cells += 1;
        if (pole.busy) {
          pole.unwritten = true;
          rep.moved = true;
        }
      } else {
        pole.busy = false;
      }
      pole.marked = false;
      pole.inP = false;
    }
  }
  rep.tiles = tileList_.size();
  totalCellSteps_ += rep.cells;
}

// ---------------------------------------------------------------------------------------------
// Drift-diffusion

double SandField::explicitBound(const Material& material, bool wholeGrid) const {
  material.validate();
  std::vector<std::uint8_t> rowUsed(std::size_t(m_) + 1, wholeGrid ? 1 : 0);
  bool polesUsed[2] = {wholeGrid, wholeGrid};
  if (!wholeGrid) {
    for (std::size_t t = 0; t < tiles_.size(); ++t) {
      if (!busy_[t] && !marked_[t]) continue;
      const int tv = int(t) / tilesU_;
      for (int v = tv * kT; v < std::min(m_ + 1, tv * kT + kT); ++v) rowUsed[std::size_t(v)] = 1;
    }
    if (grid_.sphere()) {
      for (int p = 0; p < 2; ++p) polesUsed[p] = poles_[p].busy || poles_[p].marked;
    }
  }
  return boundOverRows(material, rowUsed, polesUsed);
}

double SandField::boundOverRows(const Material& material, const std::vector<std::uint8_t>& rowUsed,
                                const bool polesUsed[2]) const {
  const double D = material.diffusion;
  if (!(D > 0.0)) return std::numeric_limits<double>::infinity();
  const double l2 = grid_.cellSize() * grid_.cellSize();
  auto gH = [&](int v) { return D * l2 * grid_.horizontalFace(v) / grid_.horizontal(v); };
  auto gV = [&](int v) { return D * l2 * grid_.verticalFace(v) / grid_.vertical(v); };
  double bound = std::numeric_limits<double>::infinity();
  for (int v = 0; v <= m_; ++v) {
    if (!rowUsed[std::size_t(v)]) continue;
    if (!grid_.ordinaryRow(v)) continue;
    double g = 2.0 * gH(v);
    if (v > 0) g += gV(v - 1);  // includes a ring cell's face to its pole
    if (v < m_) g += gV(v);
    bound = std::min(bound, grid_.area(v) / g);
  }
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) {
      if (!polesUsed[p]) continue;
      const int v = p == 0 ? 0 : m_;
      bound = std::min(bound, grid_.area(v) / (double(m_) * gV(p == 0 ? 0 : m_ - 1)));
    }
  }
  return bound;
}

void SandField::diffusionTile(int tu, int tv, const DiffusionTables& tb, double dt,
                              const PushForce* force, double* hs, std::uint8_t& busy) {
  gather(tu, tv, hs);
  const int v0 = tv * kT - 2;
  const bool sphere = grid_.sphere();
  unsigned any = 0;
  Tile& tile = *tiles_[std::size_t(tileIndex(tu, tv))];
  for (int lv = 0; lv < kT; ++lv) {
    const int r = lv + 2, v = v0 + r;
    double* out = tile.cur.get() + lv * kT - 2;  // in place: the scratch holds the old values
    if (!grid_.ordinaryRow(v)) {
      std::fill_n(out + 2, kT, kWall);
      continue;
    }
    const std::size_t i = std::size_t(v + 2);
    const kernels::DiffusionRow k{tb.gH[i], tb.invH[i], tb.gV[i - 1],   tb.invV[i - 1],
                                  tb.gV[i], tb.invV[i], dt * tb.invA[i]};
    const double* hm = hs + (r - 1) * kW;
    const double* h0 = hs + r * kW;
    const double* hp = hs + (r + 1) * kW;
    any |= kernels::diffusionRow(hm, h0, hp, out, k, tb.repose);
    if (sphere && (v == 1 || v == m_ - 1)) {
      const int p = v == 1 ? 0 : 1;
      const double* hq = p == 0 ? hm : hp;
      const double g = p == 0 ? k.gS : k.gN, inv = p == 0 ? k.invS : k.invN;
      for (int c = 2; c < kT + 2; ++c) {
        const int u = tu * kT + c - 2;
        if (u >= cols_) break;
        poleFlux_[p][std::size_t(u)] = kernels::faceFlux(h0[c], hq[c], g, inv, tb.repose);
      }
    }
    if (force) {
      for (int c = 2; c < kT + 2; ++c) {
        const int u = tu * kT + c - 2;
        if (u >= cols_) break;
        double f = 0.0;
        const int un[4] = {u - 1, u + 1, u, u};
        const int vn[4] = {v, v, v - 1, v + 1};
        for (int q = 0; q < 4; ++q) {
          int uu = un[q];
          if (sphere) uu = (uu + m_) % m_;
          if (!cellExists(uu, vn[q])) continue;
          f += driftFlux(*force, tb.zetaInv, u, v, uu, vn[q]);
        }
        if (f != 0.0) {
          out[c] -= dt * f * tb.invA[i];
          any = 1;
        }
      }
    }
  }
  busy = any ? 1 : 0;
}

double SandField::driftFlux(const PushForce& force, double zetaInv, int ua, int va, int ub,
                            int vb) const {
  // Canonical order so that both cells of a face compute the same number.
  const bool swap = (vb < va) || (vb == va && ub < ua);
  if (swap) {
    std::swap(ua, ub);
    std::swap(va, vb);
  }
  const core::Chart& chart = grid_.chart();
  const Eigen::Vector3d pa = chart.position(ua, va, 0.0), pb = chart.position(ub, vb, 0.0);
  const Eigen::Vector3d mid = 0.5 * (pa + pb);
  Eigen::Vector3d foot = force.centre;
  if (grid_.sphere()) {
    foot = chart.radius() * force.centre.normalized();
  } else {
    foot.z() = 0.0;
  }
  Eigen::Vector3d radial = mid - foot;
  if (grid_.sphere()) {
    const Eigen::Vector3d up = mid.normalized();
    radial -= radial.dot(up) * up;
  }
  const double rho = radial.norm();
  if (!(rho < force.radius) || rho == 0.0) return 0.0;
  const Eigen::Vector3d n = (pb - pa).normalized();
  const double t = rho / force.radius;
  const double prof = (1.0 - t * t) * (1.0 - t * t);
  const double fn = force.strength * prof * radial.dot(n) / rho;
  const double faceLength = va == vb ? grid_.horizontalFace(va) : grid_.verticalFace(va);
  const double flux = zetaInv * fn * grid_.cellSize() * faceLength;
  return swap ? -flux : flux;
}

void SandField::markForce(const PushForce& force) {
  const core::Chart& chart = grid_.chart();
  const auto foot = chart.inverse(force.centre);
  if (!foot) return;
  const double spacingV = grid_.sphere() ? grid_.vertical(m_ / 2) : grid_.vertical(0);
  const int dv = int(std::ceil(force.radius / spacingV)) + 2;
  const int vc = int(std::lround((*foot)(1))), uc = int(std::lround((*foot)(0)));
  terrain::GridRegion r;
  r.vBegin = std::max(0, vc - dv);
  r.vEnd = std::min(m_, vc + dv);
  double minH = std::numeric_limits<double>::infinity();
  for (int v = r.vBegin; v <= r.vEnd; ++v) {
    if (grid_.ordinaryRow(v)) minH = std::min(minH, grid_.horizontal(v));
  }
  const int du = std::isfinite(minH) ? int(std::min(1e9, std::ceil(force.radius / minH))) + 2 : m_;
  if (grid_.sphere() && (2 * du + 1 >= m_ || r.vBegin == 0 || r.vEnd == m_)) {
    r.uBegin = 0;
    r.uEnd = m_;
  } else {
    r.uBegin = uc - du;
    r.uEnd = uc + du;
    if (!grid_.sphere()) {
      r.uBegin = std::max(0, r.uBegin);
      r.uEnd = std::min(m_, r.uEnd);
    }
  }
  mark(r);
}

const SandField::DiffusionTables& SandField::diffusionTables(const Material& material) {
  if (diffusionTables_ && diffusionMaterial_ == material) return *diffusionTables_;
  auto tables = std::make_unique<DiffusionTables>();
  DiffusionTables& tb = *tables;
  tb.repose = kernels::Repose::of(material);
  tb.zetaInv = material.frictionInverse;
  const std::size_t rows = std::size_t(m_) + 5;
  for (auto* a : {&tb.gH, &tb.gV, &tb.invH, &tb.invV, &tb.invA}) a->assign(rows, 0.0);
  const double Dl2 = material.diffusion * grid_.cellSize() * grid_.cellSize();
  for (int v = 0; v <= m_; ++v) {
    const std::size_t i = std::size_t(v + 2);
    tb.invA[i] = 1.0 / grid_.area(v);
    if (grid_.ordinaryRow(v)) {
      tb.gH[i] = Dl2 * grid_.horizontalFace(v) / grid_.horizontal(v);
      tb.invH[i] = 1.0 / grid_.horizontal(v);
    }
    if (v < m_ && (grid_.ordinaryRow(v) || grid_.ordinaryRow(v + 1))) {
      tb.gV[i] = Dl2 * grid_.verticalFace(v) / grid_.vertical(v);
      tb.invV[i] = 1.0 / grid_.vertical(v);
    }
  }
  diffusionTables_ = std::move(tables);
  diffusionMaterial_ = material;
  return *diffusionTables_;
}

StepReport SandField::diffusionStep(const Material& material, double dt, DiffusionScheme scheme,
                                    StepPolicy policy, const PushForce* force) {
  material.validate();
  if (!std::isfinite(dt) || !(dt > 0.0)) {
    throw core::InputError("diffusion time step dt = " + core::exactNumber(dt) +
                           " must be finite and > 0");
  }
  if (force) {
    if (!force->centre.allFinite() || !std::isfinite(force->radius) || !(force->radius > 0.0) ||
        !std::isfinite(force->strength)) {
      throw core::InputError("push force: centre, radius (> 0) and strength must be finite");
    }
    markForce(*force);
  }
  StepReport rep;
  rep.dt = dt;
  if (atRest()) return rep;
  buildActiveSet(Predicate::kDiffusion, material);
  if (scheme == DiffusionScheme::kExplicit) {
    // The bound over the rows this step visits (the closed active set).
    std::vector<std::uint8_t> rowUsed(std::size_t(m_) + 1, 0);
    for (int t : tileList_) {
      const int tv = t / tilesU_;
      for (int v = tv * kT; v < std::min(m_ + 1, tv * kT + kT); ++v) rowUsed[std::size_t(v)] = 1;
    }
    const bool polesUsed[2] = {grid_.sphere() && poles_[0].inP, grid_.sphere() && poles_[1].inP};
    const double bound = boundOverRows(material, rowUsed, polesUsed);
    if (dt > bound) {
      if (policy == StepPolicy::kRefuse) {
        // Nothing has moved: forget the set this step would have visited.
        for (int t : tileList_) inP_[std::size_t(t)] = 0;
        tileList_.clear();
        if (grid_.sphere()) poles_[0].inP = poles_[1].inP = false;
        throw core::InputError("explicit diffusion time step dt = " + core::exactNumber(dt) +
                               " exceeds the stability bound " + core::exactNumber(bound) +
                               " (dt <= min A_i / (D l^2 sum L_f / d_f))");
      }
      if (policy == StepPolicy::kClamp) dt = bound;
    }
  }
  rep.dt = dt;
  const DiffusionTables& tb = diffusionTables(material);
  const bool sphere = grid_.sphere();
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      if (poles_[p].inP) std::fill(poleFlux_[p].begin(), poleFlux_[p].end(), 0.0);
    }
  }
  if (scheme == DiffusionScheme::kExplicit) {
    std::vector<std::uint8_t> busyOut(tileList_.size(), 0);
    const int n = int(tileList_.size());
#pragma omp parallel if (n >= kParallelTiles)
    {
      std::vector<double> hs(std::size_t(kW) * kW);
#pragma omp for schedule(static)
      for (int j = 0; j < n; ++j) tiles_[std::size_t(tileList_[std::size_t(j)])]->snapshot();
#pragma omp for schedule(dynamic, 1)
      for (int j = 0; j < n; ++j) {
        const int t = tileList_[std::size_t(j)];
        diffusionTile(t % tilesU_, t / tilesU_, tb, dt, force, hs.data(), busyOut[std::size_t(j)]);
      }
    }
    for (int j = 0; j < n; ++j)
      busy_[std::size_t(tileList_[std::size_t(j)])] = busyOut[std::size_t(j)];
    if (sphere) {
      for (int p = 0; p < 2; ++p) {
        Pole& pole = poles_[std::size_t(p)];
        if (!pole.inP) continue;
        double in = 0.0;
        bool moved = false;
        for (double f : poleFlux_[p]) {
          in += f;
          moved |= f != 0.0;
        }
        pole.h += dt * in * (1.0 / grid_.area(p == 0 ? 0 : m_));
        pole.busy = moved;
      }
    }
  } else {
    semiImplicit(tb, dt, force);
  }
  finishStep(rep);
  return rep;
}

// ---------------------------------------------------------------------------------------------
// Semi-implicit (LOD) diffusion: (I - dt L_rows) then (I - dt L_columns) then the polar caps, each
// an implicit Euler step with the face weights of the heights before the step. Each sub-step is
// a symmetric, diagonally dominant M-matrix system in the area-weighted form
//     A_i x_i + sum_f K_f (x_i - x_j) = A_i b_i,   K_f = dt D l^2 (L_f / d_f) w_f >= 0,
// so it keeps sum A_i x_i and obeys a maximum principle at any dt.

void SandField::semiImplicit(const DiffusionTables& tb, double dt, const PushForce* force) {
  const bool sphere = grid_.sphere();
  const int nTiles = int(tileList_.size());
  auto busyAt = std::make_unique<std::atomic<std::uint8_t>[]>(tiles_.size());
  for (int t : tileList_) busyAt[std::size_t(t)].store(0, std::memory_order_relaxed);
  auto setBusy = [&](int u, int v) {
    busyAt[std::size_t(tileIndex(u / kT, v / kT))].store(1, std::memory_order_relaxed);
  };
  // next = cur (+ the drift of the force, explicit: it does not depend on h).
  for (int t : tileList_) {
    Tile& tile = *tiles_[std::size_t(t)];
    if (!tile.next) tile.next = std::make_unique<double[]>(std::size_t(kT) * kT);
    std::copy_n(tile.cur.get(), kT * kT, tile.next.get());
  }
  if (force) {
    for (int j = 0; j < nTiles; ++j) {
      const int t = tileList_[std::size_t(j)];
      const int tu = t % tilesU_, tv = t / tilesU_;
      Tile& tile = *tiles_[std::size_t(t)];
      for (int lv = 0; lv < kT; ++lv) {
        const int v = tv * kT + lv;
        if (!grid_.ordinaryRow(v)) continue;
        for (int lu = 0; lu < kT; ++lu) {
          const int u = tu * kT + lu;
          if (u >= cols_) break;
          double f = 0.0;
          const int un[4] = {u - 1, u + 1, u, u};
          const int vn[4] = {v, v, v - 1, v + 1};
          for (int q = 0; q < 4; ++q) {
            int uu = un[q];
            if (sphere) uu = (uu + m_) % m_;
            if (!cellExists(uu, vn[q])) continue;
            f += driftFlux(*force, tb.zetaInv, u, v, uu, vn[q]);
          }
          if (f != 0.0) {
            tile.next[std::size_t(lv * kT + lu)] -= dt * f * tb.invA[std::size_t(v + 2)];
            busyAt[std::size_t(t)].store(1, std::memory_order_relaxed);
          }
        }
      }
    }
  }
  auto cell = [&](std::unique_ptr<double[]> Tile::*buf, int u, int v) -> double& {
    Tile& tile = *tiles_[std::size_t(tileIndex(u / kT, v / kT))];
    return (tile.*buf)[std::size_t((v % kT) * kT + (u % kT))];
  };

  // --- Rows: runs of tiles of P along each tile row.
  struct RowRun {
    int v, u0, len;  // cells u0 .. u0 + len - 1 (mod m on the sphere)
    bool circle;
  };
  std::vector<RowRun> runs;
  for (int tv = 0; tv < tilesV_; ++tv) {
    std::vector<int> in(std::size_t(tilesU_), 0);
    bool anyIn = false, allIn = true;
    for (int tu = 0; tu < tilesU_; ++tu) {
      in[std::size_t(tu)] = inP_[std::size_t(tileIndex(tu, tv))];
      anyIn |= bool(in[std::size_t(tu)]);
      allIn &= bool(in[std::size_t(tu)]);
    }
    if (!anyIn) continue;
    std::vector<std::pair<int, int>> tileRuns;  // first tile, count
    if (sphere && allIn) {
      tileRuns.push_back({0, tilesU_});
    } else if (sphere) {
      int start = 0;
      while (in[std::size_t(start)]) ++start;  // a tile outside P exists
      for (int k = 1; k <= tilesU_; ++k) {
        const int tu = (start + k) % tilesU_;
        if (!in[std::size_t(tu)]) continue;
        if (!tileRuns.empty() && (tileRuns.back().first + tileRuns.back().second) % tilesU_ == tu) {
          ++tileRuns.back().second;
        } else {
          tileRuns.push_back({tu, 1});
        }
      }
    } else {
      for (int tu = 0; tu < tilesU_; ++tu) {
        if (!in[std::size_t(tu)]) continue;
        if (!tileRuns.empty() && tileRuns.back().first + tileRuns.back().second == tu) {
          ++tileRuns.back().second;
        } else {
          tileRuns.push_back({tu, 1});
        }
      }
    }
    for (int v = tv * kT; v < std::min(m_ + 1, tv * kT + kT); ++v) {
      if (!grid_.ordinaryRow(v)) continue;
      for (auto [t0, cnt] : tileRuns) {
        const int u0 = t0 * kT;
        const int len = sphere ? cnt * kT : std::min(cols_, (t0 + cnt) * kT) - u0;
        runs.push_back({v, u0, len, sphere && cnt == tilesU_});
      }
    }
  }
  const kernels::Repose rep = tb.repose;
#pragma omp parallel if (nTiles >= kParallelTiles)
  {
    std::vector<double> x, hn, k, work;
#pragma omp for schedule(dynamic, 8)
    for (int j = 0; j < int(runs.size()); ++j) {
      const RowRun run = runs[std::size_t(j)];
      const int v = run.v;
      const std::size_t iv = std::size_t(v + 2);
      const int n = run.len;
      const int tv = v / kT, lv = v % kT;
      // The run's cells tile by tile: next (b) and cur (the heights the weights come from).
      x.resize(std::size_t(n));
      hn.resize(std::size_t(n));
      for (int i = 0; i < n; i += kT) {
        const int tu = ((run.u0 + i) / kT) % tilesU_;
        const Tile& tile = *tiles_[std::size_t(tileIndex(tu, tv))];
        const int cnt = std::min(kT, n - i);
        std::copy_n(tile.next.get() + lv * kT, cnt, x.data() + i);
        std::copy_n(tile.cur.get() + lv * kT, cnt, hn.data() + i);
      }
      const int faces = run.circle ? n : n - 1;
      const double scale = dt * tb.invA[iv] * tb.gH[iv], invH = tb.invH[iv];
      k.resize(std::size_t(n));
      bool any = false;
      for (int i = 0; i < faces; ++i) {
        const double w =
            kernels::weight(std::abs(hn[std::size_t(i)] - hn[std::size_t((i + 1) % n)]), invH, rep);
        k[std::size_t(i)] = scale * w;
        any |= w > 0.0;
      }
      if (!run.circle) k[std::size_t(n - 1)] = 0.0;
      if (!any) continue;
      auto U = [&](int i) { return sphere ? (run.u0 + i) % m_ : run.u0 + i; };
      for (int i = 0; i < faces; ++i) {
        if (k[std::size_t(i)] > 0.0) {
          setBusy(U(i), v);
          setBusy(U((i + 1) % n), v);
        }
      }
      kernels::solveRow(x, k, run.circle, work);
      for (int i = 0; i < n; i += kT) {
        const int tu = ((run.u0 + i) / kT) % tilesU_;
        Tile& tile = *tiles_[std::size_t(tileIndex(tu, tv))];
        std::copy_n(x.data() + i, std::min(kT, n - i), tile.next.get() + lv * kT);
      }
    }
  }

  // --- Columns: per tile column, runs of tiles of P, all kT columns at once.
  struct ColRun {
    int tu, v0, v1;  // ordinary rows v0 .. v1
  };
  std::vector<ColRun> cruns;
  for (int tu = 0; tu < tilesU_; ++tu) {
    int tv = 0;
    while (tv < tilesV_) {
      if (!inP_[std::size_t(tileIndex(tu, tv))]) {
        ++tv;
        continue;
      }
      int te = tv;
      while (te + 1 < tilesV_ && inP_[std::size_t(tileIndex(tu, te + 1))]) ++te;
      int v0 = tv * kT, v1 = std::min(m_, te * kT + kT - 1);
      while (v0 <= v1 && !grid_.ordinaryRow(v0)) ++v0;
      while (v1 >= v0 && !grid_.ordinaryRow(v1)) --v1;
      if (v0 <= v1) cruns.push_back({tu, v0, v1});
      tv = te + 1;
    }
  }
#pragma omp parallel if (nTiles >= kParallelTiles)
  {
    std::vector<double> x, kk, a, work;
#pragma omp for schedule(dynamic, 1)
    for (int j = 0; j < int(cruns.size()); ++j) {
      const ColRun run = cruns[std::size_t(j)];
      const int n = run.v1 - run.v0 + 1;
      const int lanes = std::min(kT, cols_ - run.tu * kT);
      x.assign(std::size_t(n) * kT, 0.0);
      kk.assign(std::size_t(n) * kT, 0.0);  // face between row i and i + 1
      a.resize(std::size_t(n));
      for (int i = 0; i < n; ++i) {
        const int v = run.v0 + i;
        a[std::size_t(i)] = grid_.area(v);
        const double* src =
            tiles_[std::size_t(tileIndex(run.tu, v / kT))]->next.get() + (v % kT) * kT;
        std::copy_n(src, kT, x.data() + std::size_t(i) * kT);
        if (i + 1 < n) {
          const double* c0 =
              tiles_[std::size_t(tileIndex(run.tu, v / kT))]->cur.get() + (v % kT) * kT;
          const double* c1 =
              tiles_[std::size_t(tileIndex(run.tu, (v + 1) / kT))]->cur.get() + ((v + 1) % kT) * kT;
          const std::size_t iv = std::size_t(v + 2);
          bool act = false;
          for (int l = 0; l < lanes; ++l) {
            const double w = kernels::weight(std::abs(c0[l] - c1[l]), tb.invV[iv], rep);
            kk[std::size_t(i) * kT + std::size_t(l)] = dt * tb.gV[iv] * w;
            act |= w > 0.0;
          }
          if (act) {
            setBusy(run.tu * kT, v);
            setBusy(run.tu * kT, v + 1);
          }
        }
      }
      kernels::solveColumns(x, kk, a, n, kT, work);
      for (int i = 0; i < n; ++i) {
        const int v = run.v0 + i;
        double* dst = tiles_[std::size_t(tileIndex(run.tu, v / kT))]->next.get() + (v % kT) * kT;
        std::copy_n(x.data() + std::size_t(i) * kT, lanes, dst);
      }
    }
  }

  // --- Polar caps: the pole and its ring, an arrow system solved exactly.
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (!pole.inP) continue;
      const int vr = p == 0 ? 1 : m_ - 1;
      const std::size_t iv = std::size_t((p == 0 ? 0 : m_ - 1) + 2);
      const double Ap = grid_.area(p == 0 ? 0 : m_), Ar = grid_.area(vr);
      double num = Ap * pole.h, den = Ap;
      std::vector<double> K(std::size_t(m_), 0.0);
      bool moved = false;
      for (int u = 0; u < m_; ++u) {
        if (!inP_[std::size_t(tileIndex(u / kT, vr / kT))]) continue;
        const double w =
            kernels::weight(std::abs(pole.h - cell(&Tile::cur, u, vr)), tb.invV[iv], rep);
        if (!(w > 0.0)) continue;
        const double Ku = dt * tb.gV[iv] * w;
        K[std::size_t(u)] = Ku;
        const double f = Ku * Ar / (Ar + Ku);
        num += f * cell(&Tile::next, u, vr);
        den += f;
        moved = true;
        setBusy(u, vr);
      }
      if (moved) {
        const double hp = num / den;
        for (int u = 0; u < m_; ++u) {
          const double Ku = K[std::size_t(u)];
          if (Ku == 0.0) continue;
          double& x = cell(&Tile::next, u, vr);
          x = (Ar * x + Ku * hp) / (Ar + Ku);
        }
        pole.h = hp;
      }
      pole.busy = moved;
    }
  }
  for (int t : tileList_) {
    busy_[std::size_t(t)] = busyAt[std::size_t(t)].load(std::memory_order_relaxed);
    Tile& tile = *tiles_[std::size_t(t)];
    std::swap(tile.cur, tile.next);
  }
}

// ---------------------------------------------------------------------------------------------
// Output

terrain::GridRegion SandField::writeBack(double limit) {
  const core::GridSize& g = grid_.grid();
  const bool sphere = grid_.sphere();
  terrain::GridRegion dirty = terrain::GridRegion::none();
  auto store = [&](int u, int v, double x) {
    const float f = static_cast<float>(std::clamp(x, -limit, limit));
    float& dst = heights_[g.index(u, v)];
    if (std::bit_cast<std::uint32_t>(f) == std::bit_cast<std::uint32_t>(dst)) return false;
    dst = f;
    return true;
  };
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    Tile* tile = tiles_[t].get();
    if (!tile || !tile->unwritten) continue;
    tile->unwritten = false;
    const int tu = int(t) % tilesU_, tv = int(t) / tilesU_;
    int ua = cols_, ub = -1, va = m_ + 1, vb = -1;
    for (int lv = 0; lv < kT; ++lv) {
      const int v = tv * kT + lv;
      if (!grid_.ordinaryRow(v)) continue;
      for (int lu = 0; lu < kT; ++lu) {
        const int u = tu * kT + lu;
        if (u >= cols_) break;
        const double x = tile->cur[std::size_t(lv * kT + lu)];
        bool changed = store(u, v, x);
        if (sphere && u == 0) changed |= store(m_, v, x);
        if (changed) {
          ua = std::min(ua, u);
          ub = std::max(ub, u);
          va = std::min(va, v);
          vb = std::max(vb, v);
        }
      }
    }
    if (vb < 0) continue;
    terrain::GridRegion r{ua, ub, va, vb};
    if (sphere && ua == 0) r = terrain::GridRegion{m_, m_ + ub, va, vb};  // names u = m too
    dirty = dirty.unite(r, g, sphere);
  }
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (!pole.resident || !pole.unwritten) continue;
      pole.unwritten = false;
      const int v = p == 0 ? 0 : m_;
      bool changed = false;
      for (int u = 0; u <= m_; ++u) changed |= store(u, v, pole.h);
      if (changed) dirty = dirty.unite(terrain::GridRegion{0, m_, v, v}, g, sphere);
    }
  }
  return dirty;
}

terrain::GridRegion SandField::release(double limit) {
  const terrain::GridRegion dirty = writeBack(limit);
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    if (busy_[t] || marked_[t]) continue;
    tiles_[t].reset();
  }
  if (grid_.sphere()) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (!pole.busy && !pole.marked) pole.resident = false;
    }
  }
  return dirty;
}

}  // namespace ps::sand
