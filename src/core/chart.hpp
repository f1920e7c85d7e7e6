#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "core/grid.hpp"

namespace ps::core {

// A parametrization of the planet's surface by a (2^n+1)^2 grid. Everything that needs to know
// where a vertex is in R^3, which grid vertices are the same point, or how to go from a point in
// space back to the grid asks the chart; a new surface shape is one new subclass.
class Chart {
 public:
  virtual ~Chart() = default;

  virtual std::string name() const = 0;
  const GridSize& grid() const { return grid_; }

  // Position in the planet frame of grid vertex (u, v) displaced by height h along up().
  virtual Eigen::Vector3d position(int u, int v, double h) const = 0;
  // position() of the grid vertices (u, v), u = uFirst .. uLast, with heights hRow[u] (hRow is
  // the row's first height): out.x[k], y[k], z[k] for u = uFirst + k. Bit-identical to
  // position(); charts override it with a loop the compiler vectorises (the error bounds fill
  // whole rows of positions).
  struct RowOut {
    double *x, *y, *z;
  };
  virtual void rowPositions(int v, int uFirst, int uLast, const float* hRow, RowOut out) const {
    for (int u = uFirst; u <= uLast; ++u) {
      const Eigen::Vector3d p = position(u, v, double(hRow[u]));
      const int k = u - uFirst;
      out.x[k] = p.x(), out.y[k] = p.y(), out.z[k] = p.z();
    }
  }
  // position() of scattered grid vertices (u[k], v[k]) with heights h[k], k < n: out.x[k],
  // y[k], z[k]. Bit-identical to position(); the tessellator asks for one level of the bintree's
  // split vertices at a time, and charts override it with a loop the compiler vectorises.
  virtual void scatteredPositions(const std::int32_t* u, const std::int32_t* v, const float* h,
                                  std::size_t n, RowOut out) const {
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d p = position(u[k], v[k], double(h[k]));
      out.x[k] = p.x(), out.y[k] = p.y(), out.z[k] = p.z();
    }
  }
  // The direction heights displace along at (u, v) (unit length).
  virtual Eigen::Vector3d up(int u, int v) const = 0;
  // Continuous version of position() for parameter coordinates in grid units.
  virtual Eigen::Vector3d positionAt(double u, double v, double h) const = 0;

  // Parameter coordinates (grid units, possibly fractional) of the surface point "under" p:
  // the inverse mapping. Returns nullopt where p has no well-defined foot point (e.g. the
  // planet's centre).
  virtual std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const = 0;

  // Topology: columns u = 0 and u = m are one meridian (the seam) when wrapsU().
  virtual bool wrapsU() const = 0;
  // Rows v = 0 and v = m each collapse to a single point (the poles) when hasPoleRows().
  virtual bool hasPoleRows() const = 0;

  // The one grid vertex that stands for every grid vertex at the same surface point as (u, v)
  // (the topology as data: welded meshes, one key per point): on a seam the chart wraps, column
  // m is column 0; on a pole row, every vertex is (0, v); a chart that glues its sides another
  // way (core/octahedral_chart.hpp) says so here. Itself elsewhere.
  virtual GridPoint canonical(int u, int v) const {
    const int m = grid_.m();
    if (hasPoleRows() && (v == 0 || v == m)) return {0, v};
    if (wrapsU() && u == m) return {0, v};
    return {u, v};
  }

  // The grid vertices at (u, v)'s surface point, itself included, into out (at most 4; the
  // count is returned): seam twins, a folded side's mirror, a point's corners. A pole row (all
  // m + 1 vertices of row 0 or m when hasPoleRows()) is the one case not listed here: it is one
  // point, and canonical() says so.
  virtual int twins(int u, int v, GridPoint out[4]) const {
    const int m = grid_.m();
    out[0] = {u, v};
    if (wrapsU() && (u == 0 || u == m)) {
      out[1] = {m - u, v};
      return 2;
    }
    return 1;
  }

  // Whether the grid's sides are glued to themselves mirrored (twins() lists the pairs): then
  // layers that keep per-vertex state combine it across each pair, as they do across a seam.
  virtual bool foldsSides() const { return false; }

  // Reference radius heights are measured from (0 for a flat chart).
  virtual double radius() const = 0;
  // Heights beyond +-heightLimit() are refused on load and saturate in edits. A sphere's is a
  // quarter of its radius (relief beyond that is not terrain); charts without a radius override.
  virtual double heightLimit() const { return 0.25 * radius(); }

 protected:
  explicit Chart(GridSize grid) : grid_(grid) {}

 private:
  GridSize grid_;
};

}  // namespace ps::core
