#include <algorithm>
#include <cmath>

#include "sand/sand_field_parts.hpp"

namespace ps::sand {

// ---------------------------------------------------------------------------------------------
// Activity

void SandField::mark(const terrain::VertexBox& region) {
  if (region.empty()) return;
  if (grid_.glued()) {
    // A change at a twin on a glued side is a change at its point: the region's images across
    // the sides hold every twin of the vertices in it.
    auto markImages = [&](int ua, int ub) {
      const core::GridBox box{std::max(0, ua), std::min(m_, ub), std::max(0, region.vBegin),
                              std::min(m_, region.vEnd)};
      core::GridBox out[4];
      const int n = grid_.chart().gluedImages(box, false, out);
      for (int i = 0; i < n; ++i)
        markRegion({out[i].uBegin, out[i].uEnd, out[i].vBegin, out[i].vEnd});
    };
    if (!grid_.tube()) {
      markImages(region.uBegin, region.uEnd);
      return;
    }
    // A tube's u seam: the region's columns unwrapped, and u = m is the point at u = 0.
    region.forEachColumnRange(grid_.grid(), [&](int a, int b) {
      markImages(a, b);
      if (b == m_ || a == m_) markImages(0, 0);
    });
    return;
  }
  markRegion(region);
}

void SandField::markRegion(const terrain::VertexBox& region) {
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
            if (!grid_.isCell(u, v)) continue;  // a glued side's twin: its point is marked
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
    if (seam) markRegion(terrain::VertexBox{0, 0, v0, v1});
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
    bool any = false;
    forEachCellOf(int(t), [&](int u, int v, std::size_t i) {
      double& x = tile->cur[i];
      const float f = heights_[g.index(u, v)];
      if (static_cast<float>(x) != f) {
        x = double(f);
        any = true;
        ++reloaded;
      }
    });
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
  if (grid_.glued()) {
    const std::function<void(int)> addTile = add;
    while (!work.empty()) {
      const int t = work.back();
      work.pop_back();
      gluedActiveSetLinks(t, pred, material, addTile);
    }
    return;
  }
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

}  // namespace ps::sand
