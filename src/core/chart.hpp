#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "core/grid.hpp"

namespace ps::core {

// How a pair of opposite sides of the grid is glued: the surface's topology, as data that the
// layers ask for instead of knowing a chart's shape.
enum class SideGluing : std::uint8_t {
  kOpen,    // a border of the surface (the flat chart; the cylinder's ends)
  kSeam,    // each side glued to the opposite one by translation: (0, v) is (m, v), or (u, 0)
            // is (u, m) (lat-long's meridian, the torus's and the cylinder's seams)
  kMirror,  // each side glued to itself mirrored at its midpoint: (u, 0) is (m - u, 0)
            // (the octahedral chart)
  kPoint,   // each side is one point (lat-long's pole rows)
};
struct Gluing {
  SideGluing uSides;  // the sides u = 0 and u = m
  SideGluing vSides;  // the sides v = 0 and v = m
};

// An inclusive box of grid vertices; u may be unwrapped across a u seam (terrain::VertexBox's
// convention: uBegin < 0 or uEnd > m continue on the other side).
struct GridBox {
  int uBegin = 0, uEnd = -1, vBegin = 0, vEnd = -1;
  friend bool operator==(const GridBox&, const GridBox&) = default;
};

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

  // How the grid's sides are glued. The default follows wrapsU() and hasPoleRows() (lat-long,
  // flat, the cylinder); charts that glue their sides otherwise say so.
  virtual Gluing gluing() const {
    return {wrapsU() ? SideGluing::kSeam : SideGluing::kOpen,
            hasPoleRows() ? SideGluing::kPoint : SideGluing::kOpen};
  }
  // Whether some side is glued in a way the seam and pole-row fast paths do not cover (a
  // mirrored side, a seam between the rows v = 0 and v = m): then layers that keep per-vertex
  // state combine it across each pair of twins() on those sides, and an edit's box stands for
  // its gluedImages() too.
  bool gluesSidesBeyondSeam() const {
    const Gluing gl = gluing();
    return gl.uSides == SideGluing::kMirror || gl.vSides == SideGluing::kMirror ||
           gl.vSides == SideGluing::kSeam;
  }
  // Whether a side is glued to itself mirrored (the octahedral chart).
  bool foldsSides() const {
    const Gluing gl = gluing();
    return gl.uSides == SideGluing::kMirror || gl.vSides == SideGluing::kMirror;
  }
  // The flips of the grid that gluedImages() uses: u -> m - u (flipU), v -> m - v (flipV).
  struct Flips {
    bool u = false, v = false;
  };
  Flips imageFlips() const {
    const Gluing gl = gluing();
    return {gl.vSides == SideGluing::kMirror,
            gl.uSides == SideGluing::kMirror || gl.vSides == SideGluing::kSeam};
  }
  // The images of `box` across the glued sides that a u seam does not cover, box first, into
  // out (at most 4; the count is returned). Across a mirrored side v = 0 or m, the grid
  // continues at u -> m - u (a side's mirror); across a seam between v = 0 and v = m at
  // v -> m - v (a box that reaches v = 0 from inside, grown by d, continues in rows m - d .. m,
  // which its reflection holds). `acrossMidlines`: also where the box reaches the flip's
  // midline (u = m/2 for u -> m - u, v = m/2 for v -> m - v). That is geometry: the octahedral
  // chart's sphere and the torus are symmetric under the flips (x -> -x, y -> -y; z -> -z), and
  // of a point and its mirror the one on a centre's side is nearer it, so a disc about a centre
  // in one part of the grid, met across a glued side or a midline, lies there inside a mirror
  // image of the centre's part (the edit's dirty box, edit::RegionGrower). Without
  // acrossMidlines (the error bounds, level by level) only the topology is used.
  // `flipsOut` (when given) receives each image's flips.
  int gluedImages(const GridBox& box, bool acrossMidlines, GridBox out[4],
                  Flips* flipsOut = nullptr) const {
    if (box.uBegin > box.uEnd || box.vBegin > box.vEnd) return 0;
    const int m = grid_.m();
    const Gluing gl = gluing();
    const Flips f = imageFlips();
    const bool reachesV = box.vBegin <= 0 || box.vEnd >= m;
    const bool reachesU = box.uBegin <= 0 || box.uEnd >= m;
    const bool uMid = box.uBegin <= m / 2 && box.uEnd >= m / 2;
    const bool vMid = box.vBegin <= m / 2 && box.vEnd >= m / 2;
    const bool flipU = f.u && (reachesV || (acrossMidlines && uMid));
    const bool flipV =
        f.v && ((gl.uSides == SideGluing::kMirror && reachesU) ||
                (gl.vSides == SideGluing::kSeam && reachesV) || (acrossMidlines && vMid));
    int n = 0;
    auto image = [&](bool u, bool v) {
      out[n] = {u ? m - box.uEnd : box.uBegin, u ? m - box.uBegin : box.uEnd,
                v ? m - box.vEnd : box.vBegin, v ? m - box.vBegin : box.vEnd};
      if (flipsOut) flipsOut[n] = {u, v};
      ++n;
    };
    image(false, false);
    if (flipU) image(true, false);
    if (flipV) image(false, true);
    if (flipU && flipV) image(true, true);
    return n;
  }
  // The grid vertex at grid position (u, v) when the grid is continued across its sides, for
  // positions outside it (a tile's apron): across a seam the other side, across a mirrored side
  // its mirror ((u, -d) is (m - u, d) across v = 0), across an open side or a pole row the
  // nearest vertex on the side (clamped).
  GridPoint continued(int u, int v) const {
    const int m = grid_.m();
    const Gluing gl = gluing();
    for (int guard = 0; guard < 8 && (u < 0 || u > m || v < 0 || v > m); ++guard) {
      if (v < 0 || v > m) {
        if (gl.vSides == SideGluing::kSeam) {
          v = ((v % m) + m) % m;
        } else if (gl.vSides == SideGluing::kMirror) {
          u = m - u, v = v < 0 ? -v : 2 * m - v;
        } else {
          v = std::clamp(v, 0, m);
        }
      } else if (gl.uSides == SideGluing::kSeam) {
        u = ((u % m) + m) % m;
      } else if (gl.uSides == SideGluing::kMirror) {
        v = m - v, u = u < 0 ? -u : 2 * m - u;
      } else {
        u = std::clamp(u, 0, m);
      }
    }
    return {std::clamp(u, 0, m), std::clamp(v, 0, m)};
  }

  // The radius of the sphere about the origin that the surface is at height 0, heights measured
  // from it (lat-long, octahedral); 0 where the surface is no such sphere (the flat chart, the
  // torus, the cylinder). It is no size of the planet: a torus's or a cylinder's 0 says "not a
  // sphere", not "small". Layers read sphereRadius() > 0 as "a sphere about the origin": the
  // tessellator's horizon occluder (a solid ball of sphereRadius() + the lowest height),
  // great-circle stroke paths, radial up in the renderer, the planet's shadow, LAT LON points of
  // a stroke script; a torus or an open tube has no such ball. What needs a size on every chart
  // takes core::boundingRadius (chart_factory.hpp) or the shape's own lengths
  // (TorusChart::majorRadius/minorRadius, CylinderChart::tubeRadius/length).
  virtual double sphereRadius() const = 0;
  // Heights beyond +-heightLimit() are refused on load and saturate in edits. A sphere's is a
  // quarter of its radius (relief beyond that is not terrain); charts that are no sphere override.
  virtual double heightLimit() const { return 0.25 * sphereRadius(); }

 protected:
  explicit Chart(GridSize grid) : grid_(grid) {}

 private:
  GridSize grid_;
};

}  // namespace ps::core
