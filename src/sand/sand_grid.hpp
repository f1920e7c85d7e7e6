#pragma once
#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "core/chart.hpp"
#include "core/grid.hpp"

namespace ps::sand {

// The cells the sand core moves material between, and their geometry, on each of the five
// charts (docs/SAND.md, "Cells, areas and the poles"):
//
// * Lat-long (a sphere of radius R): a vertex (u, v), 0 < v < m, owns the cell
//   [lat - dlat/2, lat + dlat/2] x [lon - dlon/2, lon + dlon/2] with the exact spherical area
//       A_v = 2 R^2 dlon cos(lat_v) sin(dlat/2);
//   columns u = 0 and u = m are one meridian (u = m is never a cell of its own: it copies u = 0).
//   Each pole row is ONE point that owns the polar cap of angular radius dlat/2,
//       A_pole = 4 pi R^2 sin^2(dlat/4),
//   and neighbours each of the m distinct vertices of the next row. The areas sum to 4 pi R^2.
// * Flat (FlatChart): every vertex owns a dx * dy cell; the border is closed (no flux out).
// * Octahedral (OctahedralChart, both mappings; `glued()`): the square folded onto the sphere,
//   every side glued to itself mirrored. Each distinct point (twins on the glued border are one
//   point, kept at the chart's canonical vertex) owns a quarter of every grid quad it is a corner
//   of, at each of its twins; a quad's area is that of the spherical quadrilateral through its
//   four corners (two geodesic triangles), so the areas sum to 4 pi R^2. Links (8 per cell, the
//   grid continued across the folds) and faces are per cell, not per row: a link's chord is
//   |P_i - P_j|, an axis link's face the chord between the centres of the two quads beside it.
//   The four side midpoints are cone points (180 degrees of the square around them): there the
//   continued grid reaches each neighbour twice, and only one of each pair is a link (4 links).
// * Torus and cylinder (TorusChart, CylinderChart; `glued()` and `tube()`): the same per-cell
//   links, the grid continued across the seams (the torus's both, the cylinder's u), with no
//   link across the cylinder's open rims (a closed wall: sand stays on the tube). The surfaces
//   are shift-invariant in u, so a cell's area is a function of its row: the exact area of the
//   band v +- 1/2 of one column (torus: r dalpha (R dbeta + 2 r cos(beta_v) sin(dbeta/2)); a
//   cylinder's R dalpha L/m, half of it on a rim row), summing to 4 pi^2 R r and 2 pi R L.
//   A quad's centre (faces) is its corners' mean, not projected onto the surface.
//
// "Volume" is sum_i A_i h_i over distinct points: the volume between the reference surface and the
// terrain to first order in h / R (the shell's exact volume differs by a factor 1 + h/R +
// (h/R)^2/3, 1.0016 for 10 km of relief on an Earth-sized planet). Every method here keeps this
// sum.
//
// Distances between neighbours are chords between their positions on the reference surface.
class SandGrid {
 public:
  // Throws core::InputError for a chart that is not a LatLongChart, FlatChart, OctahedralChart,
  // TorusChart or CylinderChart.
  explicit SandGrid(std::shared_ptr<const core::Chart> chart);

  const core::Chart& chart() const { return *chart_; }
  std::shared_ptr<const core::Chart> chartPtr() const { return chart_; }
  const core::GridSize& grid() const { return grid_; }
  int m() const { return m_; }
  // Lat-long: the sphere with poles and a seam (the per-row tables below).
  bool sphere() const { return sphere_; }
  // The octahedral chart, the torus and the cylinder: per-cell geometry (cellArea, neighbour,
  // chord, face), no poles.
  bool glued() const { return glued_; }
  // The torus and the cylinder: glued, u a seam, the areas per row (area(v) holds them).
  bool tube() const { return tube_; }
  // A tube's outward unit normal at a point near its reference surface (not on its axis or
  // a torus's centre circle).
  Eigen::Vector3d tubeNormal(const Eigen::Vector3d& p) const;
  // Total area (m^2) of the reference surface the cells tile.
  double surfaceArea() const { return surfaceArea_; }
  // Distinct columns: m on the sphere (u = m is u = 0), m + 1 on a flat or glued grid.
  int columns() const { return columns_; }
  // Rows whose vertices are ordinary cells (all rows on a flat grid; 1 .. m-1 on the sphere).
  bool ordinaryRow(int v) const { return v >= 0 && v <= m_ && (!sphere_ || (v > 0 && v < m_)); }

  // Area (m^2) of the cell of a vertex of row v; pole rows give the polar cap. Lat-long, flat
  // and the tubes (the per-row tables; on the octahedral chart use cellArea).
  double area(int v) const { return area_[std::size_t(v)]; }
  // Area (m^2) of the cell of grid vertex (u, v) on any chart (a twin gives its point's).
  double cellArea(int u, int v) const {
    return glued_ && !tube_ ? gluedArea(u, v) : area_[std::size_t(v)];
  }
  // Whether grid vertex (u, v) owns a cell: on a glued chart its point's canonical vertex.
  bool isCell(int u, int v) const {
    if (!glued_ || (u > 0 && u < m_ && v > 0 && v < m_)) return true;
    const core::GridPoint c = chart_->canonical(u, v);
    return c.u == u && c.v == v;
  }

  // Glued charts: the directions of a cell's links, W E S N SW SE NW NE (the first four are the
  // axis links diffusion uses; opposite pairs 0-1, 2-3, 4-7, 5-6).
  static constexpr int kDu[8] = {-1, 1, 0, 0, -1, 1, -1, 1};
  static constexpr int kDv[8] = {0, 0, -1, 1, -1, -1, 1, 1};
  // The canonical vertex of the neighbour of cell (u, v) in direction k, the grid continued
  // across the glued sides; {-1, -1} where a cone point leaves that direction out (it reaches
  // the same neighbour in the opposite direction).
  core::GridPoint neighbour(int u, int v, int k) const;
  // Links of the cell (u, v): 8, 4 at a cone point.
  int linkCount(int u, int v) const { return coneDrops(u, v) ? 4 : 8; }
  // Chord (m) of cell (u, v)'s link k; +inf where there is none. A symmetric function of the
  // two points: both cells of a link get it bit for bit.
  double chord(int u, int v, int k) const;
  // Length (m) of the face of cell (u, v)'s axis link k < 4 (0 where there is none): the chord
  // between the centres of the two grid quads beside the link, bit for bit the same from both
  // cells.
  double face(int u, int v, int k) const;
  // |a - b| with a fixed order of operations: the same bits for (a, b) and (b, a) (chord()).
  static double chordBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
  // A grid quad's centre on the sphere from its corners' points, given in the order of their
  // canonical grid indices (face()).
  Eigen::Vector3d centreOf(const Eigen::Vector3d sortedCorners[4]) const;
  // Area of the spherical quadrilateral of four reference points, in grid order (a quad's
  // corners (u, v), (u + 1, v), (u + 1, v + 1), (u, v + 1)).
  double quadAreaOf(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) const;
  // Reference position (m) of grid vertex (u, v) (twins: bit for bit one point).
  Eigen::Vector3d point(int u, int v) const { return chart_->position(u, v, 0.0); }
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
  void buildGlued(double R);
  void buildTorus(double R, double r);
  void buildCylinder(double R, double L);
  double gluedArea(int u, int v) const;
  double quadArea(int u, int v) const;         // the grid quad (u..u+1, v..v+1) on the sphere
  double computeCellArea(int u, int v) const;  // of canonical (u, v), from its quads
  // The directions a cone point leaves out (a bit per k), 0 elsewhere.
  unsigned coneDrops(int u, int v) const;
  Eigen::Vector3d quadCentre(int u, int v) const;  // the quad (u..u+1, v..v+1), continued

  std::shared_ptr<const core::Chart> chart_;
  core::GridSize grid_;
  int m_ = 0;
  bool sphere_ = false;
  bool glued_ = false;
  bool tube_ = false;
  bool openV_ = false;  // the cylinder's rims: no link beyond rows 0 and m
  double radius_ = 0;
  double surfaceArea_ = 0;
  double torusMajor_ = 0;  // the torus's major radius (tubeNormal); 0 on a cylinder
  int columns_ = 0;
  double cellSize_ = 0;
  std::vector<double> area_, horizontal_, vertical_, diagonal_, horizontalFace_, verticalFace_;
  // Glued charts: cell areas in 32 x 32 blocks computed when first asked for (a planet's grid
  // may be 8193^2, and the brush never asks), shared by copies; safe to fill from any thread.
  struct AreaCache;
  std::shared_ptr<AreaCache> areas_;
  int areaBlocksU_ = 0;
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
