#include "sand/sand_grid.hpp"

#include <cmath>
#include <numbers>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"

namespace ps::sand {

namespace {
constexpr double kPi = std::numbers::pi;
}

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
    const double R = ll->radius();
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
    return;
  }
  throw core::InputError("the sand core works on the lat-long and flat charts, not on '" +
                         chart_->name() + "'");
}

template <class T>
double SandGrid::sum(std::span<const T> h, bool absolute) const {
  if (h.size() != grid_.count()) {
    throw core::InputError("volume: got " + std::to_string(h.size()) + " heights for a " +
                           grid_.label() + " grid");
  }
  CompensatedSum total;
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
