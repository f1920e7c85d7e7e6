#pragma once
#include <memory>
#include <span>
#include <vector>

#include "core/chart.hpp"
#include "core/grid.hpp"

namespace ps::sand {

// The cells the sand core moves material between, and their geometry, on the two charts it
// knows (docs/SAND.md, "Cells, areas and the poles"):
//
// * Lat-long (a sphere of radius R): a vertex (u, v), 0 < v < m, owns the cell
//   [lat - dlat/2, lat + dlat/2] x [lon - dlon/2, lon + dlon/2] with the exact spherical area
//       A_v = 2 R^2 dlon cos(lat_v) sin(dlat/2);
//   columns u = 0 and u = m are one meridian (u = m is never a cell of its own: it copies u = 0).
//   Each pole row is ONE point that owns the polar cap of angular radius dlat/2,
//       A_pole = 4 pi R^2 sin^2(dlat/4),
//   and neighbours each of the m distinct vertices of the next row. The areas sum to 4 pi R^2.
// * Flat (FlatChart): every vertex owns a dx * dy cell; the border is closed (no flux out).
//
// "Volume" is sum_i A_i h_i over distinct points: the volume between the reference surface and the
// terrain to first order in h / R (the shell's exact volume differs by a factor 1 + h/R +
// (h/R)^2/3, 1.0016 for 10 km of relief on an Earth-sized planet). Every method here keeps this
// sum.
//
// Distances between neighbours are chords between their positions on the reference surface.
class SandGrid {
 public:
  // Throws core::InputError for a chart that is neither a LatLongChart nor a FlatChart.
  explicit SandGrid(std::shared_ptr<const core::Chart> chart);

  const core::Chart& chart() const { return *chart_; }
  std::shared_ptr<const core::Chart> chartPtr() const { return chart_; }
  const core::GridSize& grid() const { return grid_; }
  int m() const { return m_; }
  bool sphere() const { return sphere_; }
  // Distinct columns: m on the sphere (u = m is u = 0), m + 1 on a flat grid.
  int columns() const { return columns_; }
  // Rows whose vertices are ordinary cells (all rows on a flat grid; 1 .. m-1 on the sphere).
  bool ordinaryRow(int v) const { return v >= 0 && v <= m_ && (!sphere_ || (v > 0 && v < m_)); }

  // Area (m^2) of the cell of a vertex of row v; pole rows give the polar cap.
  double area(int v) const { return area_[std::size_t(v)]; }
  // Chord (m) from (u, v) to (u + 1, v).
  double horizontal(int v) const { return horizontal_[std::size_t(v)]; }
  // Chord (m) from (u, v) to (u, v + 1), 0 <= v < m (on the sphere v = 0 and v = m - 1 are the
  // links between a pole and its ring).
  double vertical(int v) const { return vertical_[std::size_t(v)]; }
  // Chord (m) from (u, v) to (u +- 1, v + 1), 0 <= v < m.
  double diagonal(int v) const { return diagonal_[std::size_t(v)]; }
  // Length (m) of the cell face between (u, v) and (u + 1, v).
  double horizontalFace(int v) const { return horizontalFace_[std::size_t(v)]; }
  // Length (m) of the face between (u, v) and (u, v + 1) (on the sphere v = 0 and m - 1: one of
  // the m faces of a polar cap).
  double verticalFace(int v) const { return verticalFace_[std::size_t(v)]; }
  // The reference spacing l (m) that diffusion constants are measured in: R pi / m (the meridian
  // spacing) on the sphere, sqrt(dx dy) on a flat grid.
  double cellSize() const { return cellSize_; }

  // sum_i A_i h_i over distinct points (seam twins and pole rows counted once), with compensated
  // summation.
  double volume(std::span<const float> heights) const;
  double volume(std::span<const double> heights) const;
  // sum_i A_i |h_i|: the scale relative volume drift is measured against.
  double absVolume(std::span<const float> heights) const;

 private:
  template <class T>
  double sum(std::span<const T> heights, bool absolute) const;

  std::shared_ptr<const core::Chart> chart_;
  core::GridSize grid_;
  int m_ = 0;
  bool sphere_ = false;
  int columns_ = 0;
  double cellSize_ = 0;
  std::vector<double> area_, horizontal_, vertical_, diagonal_, horizontalFace_, verticalFace_;
};

// Compensated (Neumaier) summation.
class CompensatedSum {
 public:
  void add(double x) {
    const double t = sum_ + x;
    if ((sum_ >= 0 ? sum_ : -sum_) >= (x >= 0 ? x : -x)) {
      carry_ += (sum_ - t) + x;
    } else {
      carry_ += (x - t) + sum_;
    }
    sum_ = t;
  }
  double value() const { return sum_ + carry_; }

 private:
  double sum_ = 0, carry_ = 0;
};

}  // namespace ps::sand
