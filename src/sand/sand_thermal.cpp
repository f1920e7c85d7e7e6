#include <algorithm>
#include <cmath>

#include "sand/sand_field_parts.hpp"

namespace ps::sand {

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
  if (grid_.glued()) return thermalStepGlued(material);
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

}  // namespace ps::sand
