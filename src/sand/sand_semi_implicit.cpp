// Semi-implicit (LOD) diffusion: (I - dt L_rows) then (I - dt L_columns) then the polar caps,
// each an implicit Euler step with the face weights of the heights before the step. Each
// sub-step is a symmetric, diagonally dominant M-matrix system in the area-weighted form
//     A_i x_i + sum_f K_f (x_i - x_j) = A_i b_i,   K_f = dt D l^2 (L_f / d_f) w_f >= 0,
// so it keeps sum A_i x_i and obeys a maximum principle at any dt.
#include <algorithm>
#include <cmath>
#include <utility>

#include "sand/sand_field_parts.hpp"

namespace ps::sand {

// One ordinary row's cells u0 .. u0 + len - 1 (mod m on the sphere) inside P; `circle`: the
// whole row of the sphere, closed on itself.
struct SandField::RowRun {
  int v, u0, len;
  bool circle;
};

// One tile column's ordinary rows v0 .. v1 inside P, all kT columns solved at once.
struct SandField::ColumnRun {
  int tu, v0, v1;
};

void SandField::semiImplicit(const DiffusionTables& tb, double dt, const PushForce* force) {
  if (grid_.glued()) {
    semiImplicitGlued(tb, dt, force);
    return;
  }
  auto busy = std::make_unique<std::atomic<std::uint8_t>[]>(tiles_.size());
  for (int t : tileList_) busy[std::size_t(t)].store(0, std::memory_order_relaxed);
  copyCurToNext();
  if (force) applyDrift(*force, tb, dt, busy);
  solveRows(rowRuns(), tb, dt, busy);
  solveColumns(columnRuns(), tb, dt, busy);
  if (grid_.sphere()) solvePolarCaps(tb, dt, busy);
  for (int t : tileList_) {
    busy_[std::size_t(t)] = busy[std::size_t(t)].load(std::memory_order_relaxed);
    Tile& tile = *tiles_[std::size_t(t)];
    std::swap(tile.cur, tile.next);
  }
}

void SandField::setBusy(BusyFlags& busy, int u, int v) const {
  busy[std::size_t(tileIndex(u / kT, v / kT))].store(1, std::memory_order_relaxed);
}

// The right-hand side starts as the heights before the step.
void SandField::copyCurToNext() {
  for (int t : tileList_) {
    Tile& tile = *tiles_[std::size_t(t)];
    if (!tile.next) tile.next = std::make_unique<double[]>(std::size_t(kT) * kT);
    std::copy_n(tile.cur.get(), kT * kT, tile.next.get());
  }
}

// The drift of the force, explicit: it does not depend on h.
void SandField::applyDrift(const PushForce& force, const DiffusionTables& tb, double dt,
                           BusyFlags& busy) {
  for (int t : tileList_) {
    Tile& tile = *tiles_[std::size_t(t)];
    forEachCellOf(t, [&](int u, int v, std::size_t i) {
      const double f = netDriftFlux(force, tb.zetaInv, u, v);
      if (f != 0.0) {
        tile.next[i] -= dt * f * tb.invA[std::size_t(v + 2)];
        busy[std::size_t(t)].store(1, std::memory_order_relaxed);
      }
    });
  }
}

// Tile row tv's runs of tiles in P (first tile, count); on the sphere a run may wrap round the
// seam, and a row of tiles all in P is one run round the whole circle.
std::vector<std::pair<int, int>> SandField::tileRunsOfRow(int tv) const {
  const bool sphere = grid_.sphere();
  std::vector<int> in(std::size_t(tilesU_), 0);
  bool anyIn = false, allIn = true;
  for (int tu = 0; tu < tilesU_; ++tu) {
    in[std::size_t(tu)] = inP_[std::size_t(tileIndex(tu, tv))];
    anyIn |= bool(in[std::size_t(tu)]);
    allIn &= bool(in[std::size_t(tu)]);
  }
  std::vector<std::pair<int, int>> tileRuns;
  if (!anyIn) return tileRuns;
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
  return tileRuns;
}

std::vector<SandField::RowRun> SandField::rowRuns() const {
  const bool sphere = grid_.sphere();
  std::vector<RowRun> runs;
  for (int tv = 0; tv < tilesV_; ++tv) {
    const std::vector<std::pair<int, int>> tileRuns = tileRunsOfRow(tv);
    if (tileRuns.empty()) continue;
    for (int v = tv * kT; v < std::min(m_ + 1, tv * kT + kT); ++v) {
      if (!grid_.ordinaryRow(v)) continue;
      for (auto [t0, cnt] : tileRuns) {
        const int u0 = t0 * kT;
        const int len = sphere ? cnt * kT : std::min(cols_, (t0 + cnt) * kT) - u0;
        runs.push_back({v, u0, len, sphere && cnt == tilesU_});
      }
    }
  }
  return runs;
}

// Each row run's tridiagonal (cyclic round the sphere) system, next -> next.
void SandField::solveRows(const std::vector<RowRun>& runs, const DiffusionTables& tb, double dt,
                          BusyFlags& busy) {
  const bool sphere = grid_.sphere();
  const kernels::Repose rep = tb.repose;
#pragma omp parallel if (int(tileList_.size()) >= kParallelTiles)
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
          setBusy(busy, U(i), v);
          setBusy(busy, U((i + 1) % n), v);
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
}

std::vector<SandField::ColumnRun> SandField::columnRuns() const {
  std::vector<ColumnRun> runs;
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
      if (v0 <= v1) runs.push_back({tu, v0, v1});
      tv = te + 1;
    }
  }
  return runs;
}

// Each column run's kT tridiagonal systems at once, next -> next.
void SandField::solveColumns(const std::vector<ColumnRun>& runs, const DiffusionTables& tb,
                             double dt, BusyFlags& busy) {
  const kernels::Repose rep = tb.repose;
#pragma omp parallel if (int(tileList_.size()) >= kParallelTiles)
  {
    std::vector<double> x, kk, a, work;
#pragma omp for schedule(dynamic, 1)
    for (int j = 0; j < int(runs.size()); ++j) {
      const ColumnRun run = runs[std::size_t(j)];
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
            setBusy(busy, run.tu * kT, v);
            setBusy(busy, run.tu * kT, v + 1);
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
}

// The pole and its ring: an arrow system, solved exactly.
void SandField::solvePolarCaps(const DiffusionTables& tb, double dt, BusyFlags& busy) {
  const kernels::Repose rep = tb.repose;
  auto cell = [&](std::unique_ptr<double[]> Tile::*buf, int u, int v) -> double& {
    Tile& tile = *tiles_[std::size_t(tileIndex(u / kT, v / kT))];
    return (tile.*buf)[std::size_t((v % kT) * kT + (u % kT))];
  };
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
      setBusy(busy, u, vr);
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

}  // namespace ps::sand
