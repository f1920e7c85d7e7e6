#pragma once
// The TIN sand tool's region: a TIN of the planet's heights over a disc of the grid, in the
// tangent plane at the disc's centre (x east, y north, z the height above the reference
// surface), that persists while the stamps of a stroke stay inside it. Made with the TIN
// export's error-bounded generation (tin/scattered_tin: every grid point of the region within
// `tolerance` of it), or from every point (tolerance 0: the TIN the tool made per stamp before).
// Its points are the region's distinct grid points at their canonical vertices; the region is
// grown across the chart's seams and folds (edit::RegionGrower), so on the octahedral chart, the
// torus and the cylinder a disc across a fold or a seam is one height field in the plane. A
// tube's patch for the view lies on the tube (the plane's points taken back to the surface
// through the chart's inverse).
//
// Writing back: every grid point takes the change of the TIN's surface since the last write
// (so the grid's own detail under the tolerance stays, and a point the TIN left out keeps its
// own), then the grid's volume, sum A h, is put back on the points that changed and the floats
// are written with the rounding carried on. The region remembers the floats it left: a grid
// that no longer holds them (an undo, another tool, a loaded planet) makes it stale.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/chart.hpp"
#include "edit/region_growing.hpp"
#include "sand/sand_grid.hpp"
#include "sand/tin_sand.hpp"
#include "terrain/mesh_patch.hpp"
#include "tin/scattered_tin.hpp"

namespace ps::sand {

// The tangent plane at a point of the reference surface.
struct TangentFrame {
  Eigen::Vector3d origin, east, north, up;
  TangentFrame(const core::Chart& chart, core::GridPoint at);
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - origin;
    return {d.dot(east), d.dot(north)};
  }
};

struct StrokeTinWrite {
  std::size_t changed = 0;      // grid points whose height changed
  double volumeCorrection = 0;  // m^3 put back after sampling the TIN onto the grid
};

class StrokeTin {
 public:
  // The region F (grown around `centre`) of `chart`'s grid with `heights`. tolerance: metres,
  // 0 for every point.
  StrokeTin(const core::Chart& chart, std::span<const float> heights, const edit::Region& F,
            core::GridPoint centre, double tolerance, const TinSandSettings& sand);

  const edit::Region& footprint() const { return footprint_; }
  const TangentFrame& frame() const { return frame_; }
  TinSand& sand() { return *sand_; }
  const TinSand& sand() const { return *sand_; }
  std::size_t gridPoints() const { return points_.size(); }
  std::size_t startVertices() const { return startVertices_; }
  const tin::ScatteredTinReport& generation() const { return generation_; }
  // The grid's points of the region, their heights as the region left them and (x, y).
  struct Point {
    int u, v;
    Eigen::Vector2d xy;
  };
  std::span<const Point> points() const { return points_; }

  // Whether `heights` still hold at every point of the region what it last wrote (or read).
  bool holds(std::span<const float> heights) const;

  // Every grid point (of the TIN's, thinned near a pole) within `radius` of `centre` that is no
  // vertex yet goes in at the grid's height, and the surface the next write-back compares with
  // is measured again: where the tool works, the TIN holds the grid's every point (what erosion
  // along edges needs to flow as on the all-points TIN), and coarse elsewhere. Returns how many.
  std::size_t densify(const Eigen::Vector2d& centre, double radius);

  // The TIN as a patch for the view (terrain/mesh_patch): its vertices on the planet (the
  // tangent plane's (x, y) taken back to the reference surface, raised by the height), standing
  // for the grid entries of the region `marginCells` equatorial cells or more inside its domain
  // (seam twins, glued sides' twins and pole rows included). On a tube it has no plane (its
  // surface is no sphere and no plane): the haptic path feels the grid there. The default two cells
  // make its border ring overlap the view's kept triangles, which closes the join
  // (docs/RENDERING.md); 0 is for measuring that.
  terrain::MeshPatch patch(double marginCells = 2) const;

  StrokeTinWrite writeBack(std::span<float> heights, const SandGrid& cells, float heightLimit);

 private:
  const core::Chart* chart_;
  edit::Region footprint_;
  TangentFrame frame_;
  double spacing_;  // m: the TIN's lattice and the pole's thinning cell (latticeSpacing)
  std::vector<Point> points_;
  std::vector<float> left_;              // the grid's height at each point as last written or read
  std::vector<double> surface_;          // the TIN's surface there then (NaN: outside its domain)
  std::vector<std::uint8_t> candidate_;  // a TIN point (not thinned out near a pole)
  std::vector<std::uint8_t> vertex_;     // inserted by densify() (or every candidate: tolerance 0)
  std::optional<TinSand> sand_;
  std::size_t startVertices_ = 0;
  tin::ScatteredTinReport generation_;
};

}  // namespace ps::sand
