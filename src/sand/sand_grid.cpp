#include "sand/sand_grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"

namespace ps::sand {

namespace {
constexpr double kPi = std::numbers::pi;

// |a - b| with a fixed order of operations: the same bits for (a, b) and (b, a).
double chordOf(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return std::sqrt((dx * dx + dy * dy) + dz * dz);
}

// Area of the spherical triangle of unit vectors a, b, c (its excess; Van Oosterom and
// Strackee's formula, the triple product through differences for small triangles).
double sphericalTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c) {
  const double det = std::abs(a.dot((b - a).cross(c - a)));
  const double den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
  return 2.0 * std::atan2(det, den);
}
}  // namespace

SandGrid::SandGrid(std::shared_ptr<const core::Chart> chart)
    : chart_(std::move(chart)), grid_(chart_ ? chart_->grid() : core::GridSize(5)) {
  if (!chart_) throw core::InputError("the sand core needs a chart");
  m_ = grid_.m();
  const std::size_t rows = std::size_t(m_) + 1;
  area_.assign(rows, 0.0);
  horizontal_.assign(rows, 0.0);
  vertical_.assign(rows, 0.0);
  diagonal_.assign(rows, 0.0);
  horizontalFace_.assign(rows, 0.0);
  verticalFace_.assign(rows, 0.0);

  if (const auto* ll = dynamic_cast<const core::LatLongChart*>(chart_.get())) {
    sphere_ = true;
    columns_ = m_;
    const double R = ll->sphereRadius();
    const double dlat = kPi / m_, dlon = 2.0 * kPi / m_;
    cellSize_ = R * dlat;
    // Evaluated from the nearer pole so that the two hemispheres get bitwise mirrored values.
    auto rho = [&](double v) { return std::sin(std::min(v, m_ - v) * dlat); };
    auto z = [&](double v) {
      const double c = std::cos(std::min(v, m_ - v) * dlat);
      return v < 0.5 * m_ ? -c : (v > 0.5 * m_ ? c : 0.0);
    };
    const double sHalfLon = std::sin(0.5 * dlon), sHalfLat = std::sin(0.5 * dlat);
    for (int v = 0; v <= m_; ++v) {
      const std::size_t i = std::size_t(v);
      if (v == 0 || v == m_) {
        const double s = std::sin(0.25 * dlat);
        area_[i] = 4.0 * kPi * R * R * s * s;
      } else {
        area_[i] = 2.0 * R * R * dlon * rho(v) * sHalfLat;
        horizontal_[i] = 2.0 * R * rho(v) * sHalfLon;
        horizontalFace_[i] = R * dlat;
      }
      if (v < m_) {
        vertical_[i] = 2.0 * R * sHalfLat;
        const double dz = z(v) - z(v + 1), dr = rho(v) - rho(v + 1);
        diagonal_[i] =
            R * std::sqrt(dz * dz + dr * dr + 4.0 * rho(v) * rho(v + 1) * sHalfLon * sHalfLon);
        verticalFace_[i] = R * rho(v + 0.5) * dlon;
      }
    }
    surfaceArea_ = 4.0 * kPi * R * R;
    return;
  }
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(chart_.get())) {
    columns_ = m_ + 1;
    const double dx = flat->dx(), dy = flat->dy();
    cellSize_ = std::sqrt(dx * dy);
    for (int v = 0; v <= m_; ++v) {
      const std::size_t i = std::size_t(v);
      area_[i] = dx * dy;
      horizontal_[i] = dx;
      horizontalFace_[i] = dy;
      if (v < m_) {
        vertical_[i] = dy;
        diagonal_[i] = std::hypot(dx, dy);
        verticalFace_[i] = dx;
      }
    }
    surfaceArea_ = double(m_) * dx * double(m_) * dy;
    return;
  }
  if (const auto* oct = dynamic_cast<const core::OctahedralChart*>(chart_.get())) {
    buildGlued(oct->sphereRadius());
    return;
  }
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(chart_.get())) {
    buildTorus(torus->majorRadius(), torus->minorRadius());
    return;
  }
  if (const auto* cyl = dynamic_cast<const core::CylinderChart*>(chart_.get())) {
    buildCylinder(cyl->tubeRadius(), cyl->length());
    return;
  }
  throw core::InputError(
      "the sand core works on the lat-long, flat, octahedral, torus and "
      "cylinder charts, not on '" +
      chart_->name() + "'");
}

struct SandGrid::AreaCache {
  static constexpr int kB = 32;
  std::vector<std::atomic<double*>> blocks;
  explicit AreaCache(std::size_t n) : blocks(n) {
    for (auto& b : blocks) b.store(nullptr, std::memory_order_relaxed);
  }
  ~AreaCache() {
    for (auto& b : blocks) delete[] b.load(std::memory_order_relaxed);
  }
  AreaCache(const AreaCache&) = delete;
  AreaCache& operator=(const AreaCache&) = delete;
};

void SandGrid::buildGlued(double R) {
  glued_ = true;
  radius_ = R;
  columns_ = m_ + 1;
  // The mean cell's side: m^2 + 2 points share 4 pi R^2.
  cellSize_ = R * std::sqrt(4.0 * kPi) / m_;
  surfaceArea_ = 4.0 * kPi * R * R;
  areaBlocksU_ = (m_ + AreaCache::kB) / AreaCache::kB;
  areas_ = std::make_shared<AreaCache>(std::size_t(areaBlocksU_) * std::size_t(areaBlocksU_));
}

void SandGrid::buildTorus(double R, double r) {
  glued_ = tube_ = true;
  torusMajor_ = R;
  columns_ = m_ + 1;
  const double dAlpha = 2.0 * kPi / m_, dBeta = 2.0 * kPi / m_;
  const double band = r * dAlpha * R * dBeta, bulge = 2.0 * r * r * dAlpha * std::sin(0.5 * dBeta);
  for (int v = 0; v <= m_; ++v) {
    // cos(beta) from the nearer of v and m - v, so that rows mirrored in z get the same bits
    // (the chart's own tables are mirrored that way too).
    const int k = std::min(v % m_, m_ - v % m_);
    area_[std::size_t(v)] = band + bulge * std::cos(dBeta * k);
  }
  surfaceArea_ = 4.0 * kPi * kPi * R * r;
  cellSize_ = std::sqrt(surfaceArea_) / m_;  // m^2 points share the surface
}

void SandGrid::buildCylinder(double R, double L) {
  glued_ = tube_ = openV_ = true;
  columns_ = m_ + 1;
  const double cell = R * (2.0 * kPi / m_) * (L / m_);
  for (int v = 0; v <= m_; ++v) area_[std::size_t(v)] = (v == 0 || v == m_) ? 0.5 * cell : cell;
  surfaceArea_ = 2.0 * kPi * R * L;
  cellSize_ = std::sqrt(surfaceArea_ / (double(m_) * double(m_ + 1)));  // m (m + 1) points
}

Eigen::Vector3d SandGrid::tubeNormal(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d axial(p.x(), p.y(), 0.0);
  const Eigen::Vector3d q = p - torusMajor_ * axial.normalized();
  return (torusMajor_ > 0.0 ? q : axial).normalized();
}

double SandGrid::chordBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return chordOf(a, b);
}

double SandGrid::quadAreaOf(const Eigen::Vector3d& pa, const Eigen::Vector3d& pb,
                            const Eigen::Vector3d& pc, const Eigen::Vector3d& pd) const {
  const double invR = 1.0 / radius_;
  const Eigen::Vector3d a = pa * invR, b = pb * invR, c = pc * invR, d = pd * invR;
  return radius_ * radius_ * (sphericalTriangle(a, b, c) + sphericalTriangle(a, c, d));
}

double SandGrid::quadArea(int u, int v) const {
  return quadAreaOf(point(u, v), point(u + 1, v), point(u + 1, v + 1), point(u, v + 1));
}

// A quarter of every grid quad beside each of the point's twins: every quad gives a quarter to
// each of its corners, so the areas sum to the quads', 4 pi R^2.
double SandGrid::computeCellArea(int u, int v) const {
  core::GridPoint tw[4];
  const int n = chart_->twins(u, v, tw);
  double area = 0.0;
  for (int k = 0; k < n; ++k) {
    for (int qv = tw[k].v - 1; qv <= tw[k].v; ++qv) {
      for (int qu = tw[k].u - 1; qu <= tw[k].u; ++qu) {
        if (qu < 0 || qv < 0 || qu >= m_ || qv >= m_) continue;
        area += 0.25 * quadArea(qu, qv);
      }
    }
  }
  return area;
}

double SandGrid::gluedArea(int u, int v) const {
  if (u <= 0 || u >= m_ || v <= 0 || v >= m_) {
    const core::GridPoint c = chart_->canonical(u, v);
    u = c.u, v = c.v;
  }
  constexpr int kB = AreaCache::kB;
  std::atomic<double*>& slot = areas_->blocks[std::size_t((v / kB) * areaBlocksU_ + u / kB)];
  const double* block = slot.load(std::memory_order_acquire);
  if (!block) {
    auto fresh = std::make_unique<double[]>(std::size_t(kB) * kB);
    // The block's quads (lower-left corners -1 .. kB - 1 from its first vertex) from its
    // points, once each; a cell inside the grid takes a quarter of its four (the sum in
    // computeCellArea's order); a cell on a glued side, whose quads lie at its twins too, asks
    // computeCellArea.
    constexpr int kP = kB + 2, kQ = kB + 1;
    const int u0 = (u / kB) * kB - 1, v0 = (v / kB) * kB - 1;
    std::vector<Eigen::Vector3d> pts(std::size_t(kP) * kP);
    for (int b = 0; b < kP; ++b) {
      for (int a = 0; a < kP; ++a) {
        const int pu = std::clamp(u0 + a, 0, m_), pv = std::clamp(v0 + b, 0, m_);
        pts[std::size_t(b * kP + a)] = point(pu, pv);
      }
    }
    std::vector<double> quads(std::size_t(kQ) * kQ);
    for (int b = 0; b < kQ; ++b) {
      for (int a = 0; a < kQ; ++a) {
        auto at = [&](int da, int db) -> const Eigen::Vector3d& {
          return pts[std::size_t((b + db) * kP + a + da)];
        };
        quads[std::size_t(b * kQ + a)] = quadAreaOf(at(0, 0), at(1, 0), at(1, 1), at(0, 1));
      }
    }
    for (int lv = 0; lv < kB; ++lv) {
      for (int lu = 0; lu < kB; ++lu) {
        const int bu = (u / kB) * kB + lu, bv = (v / kB) * kB + lv;
        double area = 0.0;
        if (bu > 0 && bu < m_ && bv > 0 && bv < m_) {
          for (int qv = lv; qv <= lv + 1; ++qv) {
            for (int qu = lu; qu <= lu + 1; ++qu) area += 0.25 * quads[std::size_t(qv * kQ + qu)];
          }
        } else if (bu <= m_ && bv <= m_ && isCell(bu, bv)) {
          area = computeCellArea(bu, bv);
        }
        fresh[std::size_t(lv * kB + lu)] = area;
      }
    }
    double* expected = nullptr;
    if (slot.compare_exchange_strong(expected, fresh.get(), std::memory_order_acq_rel)) {
      block = fresh.release();
    } else {
      block = expected;  // another thread filled it first (the same values)
    }
  }
  return block[std::size_t((v % kB) * kB + u % kB)];
}

unsigned SandGrid::coneDrops(int u, int v) const {
  if (!glued_ || tube_) return 0;
  const int h = m_ / 2;
  // Pairs of directions that reach one neighbour (the side's half turn about the point): keep
  // one of each pair (W E, S N, SW NE, SE NW).
  constexpr unsigned W = 1, E = 2, S = 4, N = 8, SW = 16, SE = 32, NW = 64, NE = 128;
  if (u == h && v == 0) return E | S | SW | SE;
  if (u == h && v == m_) return E | N | NW | NE;
  if (u == 0 && v == h) return W | N | SW | NW;
  if (u == m_ && v == h) return E | N | SE | NE;
  return 0;
}

core::GridPoint SandGrid::neighbour(int u, int v, int k) const {
  if (u > 1 && u < m_ - 1 && v > 1 && v < m_ - 1) return {u + kDu[k], v + kDv[k]};  // inside
  if ((coneDrops(u, v) >> k) & 1u) return {-1, -1};
  if (openV_ && (v + kDv[k] < 0 || v + kDv[k] > m_)) return {-1, -1};  // the rim: a wall
  const core::GridPoint p = chart_->continued(u + kDu[k], v + kDv[k]);
  return chart_->canonical(p.u, p.v);
}

double SandGrid::chord(int u, int v, int k) const {
  const core::GridPoint n = neighbour(u, v, k);
  if (n.u < 0) return std::numeric_limits<double>::infinity();
  return chordOf(point(u, v), point(n.u, n.v));
}

Eigen::Vector3d SandGrid::quadCentre(int u, int v) const {
  std::size_t idx[4];
  const int cu[4] = {u, u + 1, u + 1, u}, cv[4] = {v, v, v + 1, v + 1};
  for (int k = 0; k < 4; ++k) {
    const core::GridPoint c = chart_->continued(cu[k], cv[k]);
    const core::GridPoint p = chart_->canonical(c.u, c.v);
    idx[k] = grid_.index(p.u, p.v);
  }
  std::sort(idx, idx + 4);  // the same sum from every side
  Eigen::Vector3d corners[4];
  for (int k = 0; k < 4; ++k) {
    corners[k] = point(int(idx[k] % std::size_t(m_ + 1)), int(idx[k] / std::size_t(m_ + 1)));
  }
  return centreOf(corners);
}

Eigen::Vector3d SandGrid::centreOf(const Eigen::Vector3d sortedCorners[4]) const {
  Eigen::Vector3d s(0, 0, 0);
  for (int k = 0; k < 4; ++k) s += sortedCorners[k];
  if (tube_) return 0.25 * s;
  const double len = std::sqrt((s.x() * s.x() + s.y() * s.y()) + s.z() * s.z());
  return s * (radius_ / len);
}

double SandGrid::face(int u, int v, int k) const {
  if (k >= 4 || neighbour(u, v, k).u < 0) return 0.0;
  const int du = kDu[k], dv = kDv[k];
  const int nu = -dv, nv = du;  // the link's normal in the grid
  // The quads beside the link: corners {p, p + d, p + n, p + d + n} and the same with -n.
  auto lowerLeft = [&](int su, int sv) {
    return core::GridPoint{u + std::min({0, du, su, du + su}), v + std::min({0, dv, sv, dv + sv})};
  };
  const core::GridPoint q1 = lowerLeft(nu, nv), q2 = lowerLeft(-nu, -nv);
  return chordOf(quadCentre(q1.u, q1.v), quadCentre(q2.u, q2.v));
}

template <class T>
double SandGrid::sum(std::span<const T> h, bool absolute) const {
  if (h.size() != grid_.count()) {
    throw core::InputError("volume: got " + std::to_string(h.size()) + " heights for a " +
                           grid_.label() + " grid");
  }
  CompensatedSum total;
  if (glued_) {
    for (int v = 0; v <= m_; ++v) {
      const T* p = h.data() + grid_.index(0, v);
      for (int u = 0; u <= m_; ++u) {
        if ((u == 0 || u == m_ || v == 0 || v == m_) && !isCell(u, v)) continue;
        total.add(cellArea(u, v) * (absolute ? std::abs(double(p[u])) : double(p[u])));
      }
    }
    return total.value();
  }
  for (int v = 0; v <= m_; ++v) {
    CompensatedSum row;
    const T* p = h.data() + grid_.index(0, v);
    if (sphere_ && (v == 0 || v == m_)) {
      row.add(absolute ? std::abs(double(p[0])) : double(p[0]));
    } else {
      for (int u = 0; u < columns_; ++u) row.add(absolute ? std::abs(double(p[u])) : double(p[u]));
    }
    total.add(area_[std::size_t(v)] * row.value());
  }
  return total.value();
}

double SandGrid::volume(std::span<const float> heights) const {
  return sum(heights, false);
}
double SandGrid::volume(std::span<const double> heights) const {
  return sum(heights, false);
}
double SandGrid::absVolume(std::span<const float> heights) const {
  return sum(heights, true);
}

}  // namespace ps::sand
