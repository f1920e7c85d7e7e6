#include "haptics/terrain_patch.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/cylinder_chart.hpp"
#include "core/torus_chart.hpp"
#include "sand/displacement.hpp"

namespace ps::haptics {

bool TerrainPatch::capture(const terrain::Terrain& terrain, const Eigen::Vector3d& centre,
                           int halfSize, const terrain::MeshPatch* surface) {
  valid_ = false;
  tris_.clear();
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
  if (surface && surface->plane && surface->xy.size() == surface->positions.size() &&
      surface->heights.size() == surface->positions.size()) {
    // The grid's reach (halfSize largest spacings) and one cell more, so that the surface's
    // triangles cover every foot point the grid's box does.
    captureSurface(*surface, centre, (std::max(2, halfSize) + 1) * sand::largestSpacing(chart));
  }
  static std::atomic<std::uint64_t> captures{0};
  serial_ = captures.fetch_add(1, std::memory_order_relaxed) + 1;
  valid_ = true;
  return true;
}

void TerrainPatch::captureSurface(const terrain::MeshPatch& s, const Eigen::Vector3d& centre,
                                  double reach) {
  plane_ = *s.plane;
  const auto c = surfacePlanePoint(centre);
  if (!c) return;
  const double x0 = c->x() - reach, x1 = c->x() + reach, y0 = c->y() - reach, y1 = c->y() + reach;
  double lox = std::numeric_limits<double>::infinity(), loy = lox, hix = -lox, hiy = -lox;
  for (std::size_t t = 0; t + 2 < s.indices.size(); t += 3) {
    const std::uint32_t i = s.indices[t], j = s.indices[t + 1], k = s.indices[t + 2];
    const Eigen::Vector2d &a = s.xy[i], &b = s.xy[j], &d = s.xy[k];
    const double tx0 = std::min({a.x(), b.x(), d.x()}), tx1 = std::max({a.x(), b.x(), d.x()});
    const double ty0 = std::min({a.y(), b.y(), d.y()}), ty1 = std::max({a.y(), b.y(), d.y()});
    if (tx1 < x0 || tx0 > x1 || ty1 < y0 || ty0 > y1) continue;
    tris_.push_back(
        {a.x(), a.y(), b.x(), b.y(), d.x(), d.y(), s.heights[i], s.heights[j], s.heights[k]});
    lox = std::min(lox, tx0), hix = std::max(hix, tx1);
    loy = std::min(loy, ty0), hiy = std::max(hiy, ty1);
  }
  if (tris_.empty()) return;
  // About two triangles a bucket; at most 1024 buckets a side.
  const double w = hix - lox, h = hiy - loy;
  const double perBucket = std::sqrt(w * h / std::max(1.0, 0.5 * double(tris_.size())));
  bucketSize_ = std::max({perBucket, std::max(w, h) / 1024.0, 1e-9});
  nbx_ = std::clamp(int(std::ceil(w / bucketSize_)), 1, 1024);
  nby_ = std::clamp(int(std::ceil(h / bucketSize_)), 1, 1024);
  bx0_ = lox;
  by0_ = loy;
  // A triangle goes into every bucket its bounds touch, widened a little so that a point on a
  // bucket's edge finds the triangles on either side.
  const double pad = 1e-9 * bucketSize_;
  auto bucketsOf = [&](const Tri& t, int& i0, int& i1, int& j0, int& j1) {
    const double tx0 = std::min({t.ax, t.bx, t.cx}) - pad, tx1 = std::max({t.ax, t.bx, t.cx}) + pad;
    const double ty0 = std::min({t.ay, t.by, t.cy}) - pad, ty1 = std::max({t.ay, t.by, t.cy}) + pad;
    i0 = std::clamp(int(std::floor((tx0 - bx0_) / bucketSize_)), 0, nbx_ - 1);
    i1 = std::clamp(int(std::floor((tx1 - bx0_) / bucketSize_)), 0, nbx_ - 1);
    j0 = std::clamp(int(std::floor((ty0 - by0_) / bucketSize_)), 0, nby_ - 1);
    j1 = std::clamp(int(std::floor((ty1 - by0_) / bucketSize_)), 0, nby_ - 1);
  };
  bucketStart_.assign(std::size_t(nbx_) * std::size_t(nby_) + 1, 0);
  for (const Tri& t : tris_) {
    int i0, i1, j0, j1;
    bucketsOf(t, i0, i1, j0, j1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) ++bucketStart_[std::size_t(j) * nbx_ + i + 1];
  }
  for (std::size_t b = 1; b < bucketStart_.size(); ++b) bucketStart_[b] += bucketStart_[b - 1];
  bucketTris_.resize(bucketStart_.back());
  bucketFill_.assign(bucketStart_.begin(), bucketStart_.end() - 1);
  for (std::size_t n = 0; n < tris_.size(); ++n) {
    int i0, i1, j0, j1;
    bucketsOf(tris_[n], i0, i1, j0, j1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        bucketTris_[bucketFill_[std::size_t(j) * nbx_ + i]++] = std::uint32_t(n);
  }
}

std::optional<Eigen::Vector2d> TerrainPatch::surfacePlanePoint(const Eigen::Vector3d& p) const {
  if (plane_.radius > 0) {
    const double n = p.norm();
    if (!(n > 0) || !std::isfinite(n)) return std::nullopt;
    const Eigen::Vector3d d = p / n;
    if (!(d.dot(plane_.up) > 0)) return std::nullopt;
    return Eigen::Vector2d(plane_.radius * d.dot(plane_.east), plane_.radius * d.dot(plane_.north));
  }
  const Eigen::Vector3d q = p - plane_.origin;
  return Eigen::Vector2d(q.dot(plane_.east), q.dot(plane_.north));
}

std::optional<double> TerrainPatch::surfaceHeightAt(const Eigen::Vector2d& xy) const {
  if (tris_.empty() || !xy.allFinite()) return std::nullopt;
  const double px = xy.x(), py = xy.y();
  const double fx = (px - bx0_) / bucketSize_, fy = (py - by0_) / bucketSize_;
  if (!(fx > -1e-6 && fy > -1e-6 && fx < nbx_ + 1e-6 && fy < nby_ + 1e-6)) return std::nullopt;
  const int i = std::clamp(int(fx), 0, nbx_ - 1), j = std::clamp(int(fy), 0, nby_ - 1);
  const std::size_t b = std::size_t(j) * nbx_ + i;
  // A point on an edge shared by two triangles is in both; either gives the same height.
  constexpr double kEps = 1e-12;
  for (std::uint32_t k = bucketStart_[b]; k < bucketStart_[b + 1]; ++k) {
    const Tri& t = tris_[bucketTris_[k]];
    const double d = (t.bx - t.ax) * (t.cy - t.ay) - (t.cx - t.ax) * (t.by - t.ay);
    if (d == 0) continue;
    const double la = ((t.bx - px) * (t.cy - py) - (t.cx - px) * (t.by - py)) / d;
    const double lb = ((t.cx - px) * (t.ay - py) - (t.ax - px) * (t.cy - py)) / d;
    const double lc = 1 - la - lb;
    if (la >= -kEps && lb >= -kEps && lc >= -kEps) return la * t.ha + lb * t.hb + lc * t.hc;
  }
  return std::nullopt;
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
  if (!tris_.empty()) {
    const auto xy = surfacePlanePoint(p);
    if (const auto th = xy ? surfaceHeightAt(*xy) : std::nullopt) {
      SurfaceProbe s;
      s.uv = *uv;
      if (plane_.radius > 0) {
        // Radial, as on the grid: d = R + h - |p|.
        const double n = p.norm();
        s.up = p / n;
        s.surface = (plane_.radius + *th) * s.up;
        s.depth = plane_.radius + *th - n;
      } else {
        s.up = plane_.up;
        s.surface =
            plane_.origin + xy->x() * plane_.east + xy->y() * plane_.north + *th * plane_.up;
        s.depth = (s.surface - p).dot(s.up);
      }
      return s;
    }
  }
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
