#include "sand/sand_field.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "core/input_error.hpp"
#include "edit/undo_journal.hpp"

#include "sand/sand_field_parts.hpp"

namespace ps::sand {

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
  return u >= 0 && u < cols_ && grid_.ordinaryRow(v) && grid_.isCell(u, v);
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
  if (grid_.glued()) {
    if (geometryEverywhere_ || gluedBorderTile(tu, tv)) {
      loadGeometry(*ptr, t);
    } else {
      loadInnerLinks(*ptr, t);
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
  if (grid_.glued()) {
    const core::GridPoint c = grid_.chart().canonical(u, v);
    return value(c.u, c.v);
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
  if (grid_.glued()) {
    for (int v = 0; v <= m_; ++v) {
      for (int u = 0; u <= m_; ++u) {
        if (grid_.isCell(u, v)) total.add(grid_.cellArea(u, v) * value(u, v));
      }
    }
    return total.value();
  }
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
    if (t->geo) bytes += std::size_t(kGeoPlanes) * kT * kT * sizeof(double);
    if (t->s) bytes += std::size_t(kT) * kT * sizeof(double);
    if (t->capHalo) bytes += std::size_t(kW) * kW * sizeof(double);
    if (t->thermalPlanes) bytes += std::size_t(kThermalPlanes) * kW * kW * sizeof(double);
    bytes += t->haloSource.size() * sizeof(std::uint32_t);
  }
  if (gluedLines_) bytes += gluedLines_->bytes();
  return bytes;
}

std::size_t SandField::residentTiles() const {
  return std::size_t(
      std::count_if(tiles_.begin(), tiles_.end(), [](const auto& t) { return bool(t); }));
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
// Output

terrain::VertexBox SandField::writeBack(double limit, std::vector<edit::HeightChange>* changes) {
  const core::GridSize& g = grid_.grid();
  const bool sphere = grid_.sphere(), glued = grid_.glued();
  terrain::VertexBox dirty = terrain::VertexBox::none();
  // Each height is rounded to float with the volume its rounding loses carried to the next one
  // (error diffusion, carry_ kept from one write-back to the next): the floats' volume then
  // stays within a few cells' rounding of the volume the steps conserve (in the doubles, which
  // stay as they are), instead of wandering by every cell's rounding at every commit.
  // A height its float already holds exactly is left alone: the carry lands only on heights
  // that changed (elsewhere it would change floats, and their bounds, that nothing moved).
  auto round = [&](int u, int v, double x) {
    const float old = heights_[g.index(u, v)];
    if (double(old) == x) return old;
    const double area = grid_.cellArea(u, v), want = x + carry_ / area;
    const float f = static_cast<float>(std::clamp(want, -limit, limit));
    if (std::abs(want) < limit) carry_ += area * (x - double(f));
    return f;
  };
  auto store = [&](int u, int v, float f) {
    const std::size_t k = g.index(u, v);
    float& dst = heights_[k];
    if (std::bit_cast<std::uint32_t>(f) == std::bit_cast<std::uint32_t>(dst)) return false;
    if (changes) changes->push_back({std::uint32_t(k), dst, f});
    dst = f;
    return true;
  };
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    Tile* tile = tiles_[t].get();
    if (!tile || !tile->unwritten) continue;
    tile->unwritten = false;
    int ua = cols_, ub = -1, va = m_ + 1, vb = -1;
    forEachCellOf(int(t), [&](int u, int v, std::size_t i) {
      const float f = round(u, v, tile->cur[i]);
      bool changed = store(u, v, f);
      if (sphere && u == 0) changed |= store(m_, v, f);
      if (glued && (u == 0 || u == m_ || v == 0 || v == m_)) {
        // Its twins across the folds; the box names the canonical vertex only, whose images
        // (Terrain::commitEdit's gluedImages) hold them.
        core::GridPoint tw[4];
        const int n = grid_.chart().twins(u, v, tw);
        for (int k = 1; k < n; ++k) changed |= store(tw[k].u, tw[k].v, f);
      }
      if (changed) {
        ua = std::min(ua, u);
        ub = std::max(ub, u);
        va = std::min(va, v);
        vb = std::max(vb, v);
      }
    });
    if (vb < 0) continue;
    terrain::VertexBox r{ua, ub, va, vb};
    const bool seam = sphere || grid_.tube();  // u = m is the point at u = 0
    if (seam && ua == 0) r = terrain::VertexBox{m_, m_ + ub, va, vb};  // names u = m too
    dirty = dirty.unite(r, g, seam);
  }
  if (sphere) {
    for (int p = 0; p < 2; ++p) {
      Pole& pole = poles_[std::size_t(p)];
      if (!pole.resident || !pole.unwritten) continue;
      pole.unwritten = false;
      const int v = p == 0 ? 0 : m_;
      const float f = round(0, v, pole.h);
      bool changed = false;
      for (int u = 0; u <= m_; ++u) changed |= store(u, v, f);
      if (changed) dirty = dirty.unite(terrain::VertexBox{0, m_, v, v}, g, sphere);
    }
  }
  return dirty;
}

terrain::VertexBox SandField::release(double limit) {
  const terrain::VertexBox dirty = writeBack(limit);
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
