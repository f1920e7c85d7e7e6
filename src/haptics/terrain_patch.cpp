#include "haptics/terrain_patch.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

namespace ps::haptics {

bool TerrainPatch::capture(const terrain::Terrain& terrain, const Eigen::Vector3d& centre,
                           int halfSize) {
  valid_ = false;
  const core::Chart& chart = terrain.chart();
  const auto uv = chart.inverse(centre);
  if (!uv) return false;
  chart_ = &chart;
  revision_ = terrain.revision();
  m_ = chart.grid().m();
  wraps_ = chart.wrapsU();
  const int k = std::max(2, halfSize);
  const int cu = int(std::floor((*uv)(0))), cv = int(std::floor((*uv)(1)));
  v0_ = std::max(0, cv - k);
  const int v1 = std::min(m_, cv + 1 + k);
  rows_ = v1 - v0_ + 1;
  int ku = k;
  bool fullRows = false;
  if (chart.hasPoleRows()) {
    // A cell in u is cos(latitude) times narrower than one in v: widen by the worst row.
    if (v0_ == 0 || v1 == m_) {
      fullRows = true;
    } else {
      const double latA = std::abs(double(v0_) / m_ - 0.5) * std::numbers::pi;
      const double latB = std::abs(double(v1) / m_ - 0.5) * std::numbers::pi;
      const double c = std::cos(std::max(latA, latB));
      const double widened = double(k) / std::max(c, 1e-9);
      if (widened >= 0.5 * m_) {
        fullRows = true;
      } else {
        ku = int(std::ceil(widened));
      }
    }
  }
  if (fullRows || (wraps_ && 2 * ku + 2 > m_)) {
    u0_ = 0;
    cols_ = m_ + 1;
  } else if (wraps_) {
    u0_ = cu - ku;
    cols_ = 2 * ku + 2;
  } else {
    u0_ = std::max(0, cu - ku);
    cols_ = std::min(m_, cu + 1 + ku) - u0_ + 1;
  }
  heights_.resize(std::size_t(rows_) * std::size_t(cols_));
  const std::span<const float> h = terrain.heights();
  const core::GridSize g = chart.grid();
  for (int r = 0; r < rows_; ++r) {
    const int v = v0_ + r;
    float* dst = heights_.data() + std::size_t(r) * cols_;
    if (!wraps_ || (u0_ >= 0 && u0_ + cols_ - 1 <= m_)) {
      std::copy_n(h.data() + g.index(u0_, v), cols_, dst);
    } else {
      for (int c = 0; c < cols_; ++c) {
        const int u = ((u0_ + c) % m_ + m_) % m_;
        dst[c] = h[g.index(u, v)];
      }
    }
  }
  static std::atomic<std::uint64_t> captures{0};
  serial_ = captures.fetch_add(1, std::memory_order_relaxed) + 1;
  valid_ = true;
  return true;
}

std::optional<double> TerrainPatch::heightAt(double u, double v) const {
  if (!valid_ || !std::isfinite(u) || !std::isfinite(v)) return std::nullopt;
  double fu = u - u0_;
  if (wraps_ && cols_ != m_ + 1) {
    // Bring u into [u0, u0 + m): the patch may straddle the seam.
    fu = std::fmod(fu, double(m_));
    if (fu < 0) fu += m_;
  }
  const double fv = v - v0_;
  int c = int(std::floor(fu)), r = int(std::floor(fv));
  // Points on the last row/column use the cell before it.
  if (c == cols_ - 1 && fu <= cols_ - 1) c = cols_ - 2;
  if (r == rows_ - 1 && fv <= rows_ - 1) r = rows_ - 2;
  if (c < 0 || r < 0 || c + 1 >= cols_ || r + 1 >= rows_) return std::nullopt;
  const double a = fu - c, b = fv - r;
  const double h0 = (1 - a) * at(c, r) + a * at(c + 1, r);
  const double h1 = (1 - a) * at(c, r + 1) + a * at(c + 1, r + 1);
  return (1 - b) * h0 + b * h1;
}

std::optional<SurfaceProbe> TerrainPatch::probe(const Eigen::Vector3d& p) const {
  if (!valid_ || !p.allFinite()) return std::nullopt;
  const auto uv = chart_->inverse(p);
  if (!uv) return std::nullopt;
  const auto h = heightAt((*uv)(0), (*uv)(1));
  if (!h) return std::nullopt;
  SurfaceProbe s;
  s.uv = *uv;
  s.surface = chart_->positionAt(s.uv(0), s.uv(1), *h);
  const Eigen::Vector3d above = chart_->positionAt(s.uv(0), s.uv(1), *h + 1.0);
  s.up = (above - s.surface).normalized();
  s.depth = (s.surface - p).dot(s.up);
  return s;
}

}  // namespace ps::haptics
