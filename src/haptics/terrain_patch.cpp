#include "haptics/terrain_patch.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

#include "core/cylinder_chart.hpp"
#include "core/torus_chart.hpp"

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
  wrapsV_ = chart.gluing().vSides == core::SideGluing::kSeam;  // the torus
  int k = std::max(2, halfSize);
  int ku = k;
  // halfSize counts the chart's largest spacing (sand::largestSpacing); a tube's steps are
  // shorter round the tube or along it, and a torus's round its inner equator.
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart)) {
    const double R = torus->majorRadius(), r = torus->minorRadius();
    ku = int(std::ceil(k * (R + r) / (R - r)));
    k = int(std::ceil(k * (R + r) / r));
  } else if (const auto* cyl = dynamic_cast<const core::CylinderChart*>(&chart)) {
    const double round = 2.0 * std::numbers::pi * cyl->tubeRadius(), along = cyl->length();
    ku = int(std::ceil(k * std::max(round, along) / round));
    k = int(std::ceil(k * std::max(round, along) / along));
  }
  const int cu = int(std::floor((*uv)(0))), cv = int(std::floor((*uv)(1)));
  if (wrapsV_ && 2 * k + 2 <= m_) {
    // Rows taken modulo m across the torus's v seam, as columns are across the u seam.
    v0_ = cv - k;
    rows_ = 2 * k + 2;
  } else {
    v0_ = std::max(0, cv - k);
    const int vLast = std::min(m_, cv + 1 + k);
    rows_ = vLast - v0_ + 1;
    if (wrapsV_) v0_ = 0, rows_ = m_ + 1;
  }
  const int v1 = v0_ + rows_ - 1;
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
    const int v = wrapsV_ ? ((v0_ + r) % m_ + m_) % m_ : v0_ + r;
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
  // The box's images across glued sides (the octahedral chart's folds), after it in heights_.
  images_ = 0;
  if (!wraps_ && chart.gluesSidesBeyondSeam()) {
    core::GridBox out[4];
    const int n = chart.gluedImages({u0_, u0_ + cols_ - 1, v0_, v0_ + rows_ - 1}, false, out);
    std::size_t offset = heights_.size();
    for (int i = 1; i < n; ++i) {
      Image& b = image_[images_++];
      b = {out[i].uBegin, out[i].vBegin, out[i].uEnd - out[i].uBegin + 1,
           out[i].vEnd - out[i].vBegin + 1, offset};
      offset += std::size_t(b.cols) * std::size_t(b.rows);
    }
    heights_.resize(offset);
    for (int i = 0; i < images_; ++i) {
      const Image& b = image_[i];
      for (int r = 0; r < b.rows; ++r) {
        std::copy_n(h.data() + g.index(b.u0, b.v0 + r), b.cols,
                    heights_.data() + b.offset + std::size_t(r) * std::size_t(b.cols));
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
  double fv = v - v0_;
  if (wrapsV_ && rows_ != m_ + 1) {
    fv = std::fmod(fv, double(m_));
    if (fv < 0) fv += m_;
  }
  int c = int(std::floor(fu)), r = int(std::floor(fv));
  // Points on the last row/column use the cell before it.
  if (c == cols_ - 1 && fu <= cols_ - 1) c = cols_ - 2;
  if (r == rows_ - 1 && fv <= rows_ - 1) r = rows_ - 2;
  if (c < 0 || r < 0 || c + 1 >= cols_ || r + 1 >= rows_) {
    for (int i = 0; i < images_; ++i) {
      if (const auto x = heightInImage(image_[i], u, v)) return x;
    }
    return std::nullopt;
  }
  const double a = fu - c, b = fv - r;
  const double h0 = (1 - a) * at(c, r) + a * at(c + 1, r);
  const double h1 = (1 - a) * at(c, r + 1) + a * at(c + 1, r + 1);
  return (1 - b) * h0 + b * h1;
}

std::optional<double> TerrainPatch::heightInImage(const Image& im, double u, double v) const {
  const double fu = u - im.u0, fv = v - im.v0;
  int c = int(std::floor(fu)), r = int(std::floor(fv));
  if (c == im.cols - 1 && fu <= im.cols - 1) c = im.cols - 2;
  if (r == im.rows - 1 && fv <= im.rows - 1) r = im.rows - 2;
  if (c < 0 || r < 0 || c + 1 >= im.cols || r + 1 >= im.rows) return std::nullopt;
  auto q = [&](int cc, int rr) {
    return double(heights_[im.offset + std::size_t(rr) * std::size_t(im.cols) + std::size_t(cc)]);
  };
  const double a = fu - c, b = fv - r;
  const double h0 = (1 - a) * q(c, r) + a * q(c + 1, r);
  const double h1 = (1 - a) * q(c, r + 1) + a * q(c + 1, r + 1);
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
