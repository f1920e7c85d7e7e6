#pragma once
#include <Eigen/Core>

#include "core/chart.hpp"

namespace ps::core {

// A sphere without poles: the square grid folded onto an octahedron. With (x, y) = (2u/m - 1,
// 2v/m - 1), the diamond |x| + |y| <= 1 is the northern hemisphere (its centre the north
// pole), the four corner triangles fold onto the southern one (the four corners are the south
// pole), and each side of the square is glued to itself, mirrored at its midpoint: (u, 0) is
// (m - u, 0), (u, m) is (m - u, m), (0, v) is (0, m - v), (m, v) is (m, m - v). No row shrinks
// to a point and no seam bunches samples; the creases |x| + |y| = 1 and x = 0, y = 0 are edges
// of the 4-8 mesh from level 3 on.
//
// Two mappings of the octahedron to the sphere:
//   * equal area (the default; Clarberg 2008's octahedral equal-area map): every grid cell
//     covers the same area of the sphere; cells shear along the creases;
//   * central projection (the octahedron's point normalised): cells 5x larger at the face
//     centres than at the octahedron's vertices.
// docs/CHARTS.md has both measured against lat-long at 8193^2.
class OctahedralChart final : public Chart {
 public:
  enum class Mapping { kEqualArea, kCentral };

  // Throws InputError for a non-positive or non-finite radius.
  OctahedralChart(GridSize grid, double radius, Mapping mapping = Mapping::kEqualArea);

  std::string name() const override {
    return mapping_ == Mapping::kEqualArea ? "octahedral" : "octahedral-central";
  }
  Eigen::Vector3d position(int u, int v, double h) const override {
    return (radius_ + h) * direction(u, v);
  }
  Eigen::Vector3d up(int u, int v) const override { return direction(u, v); }
  // position() over a row and over scattered vertices: on the equal-area mapping loops the
  // compiler vectorises (cloned for AVX2 and AVX-512), bit for bit position()'s.
  void rowPositions(int v, int uFirst, int uLast, const float* hRow, RowOut out) const override;
  void scatteredPositions(const std::int32_t* u, const std::int32_t* v, const float* h,
                          std::size_t n, RowOut out) const override;
  Eigen::Vector3d positionAt(double u, double v, double h) const override;
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override;
  bool wrapsU() const override { return false; }
  bool hasPoleRows() const override { return false; }
  Gluing gluing() const override { return {SideGluing::kMirror, SideGluing::kMirror}; }
  GridPoint canonical(int u, int v) const override;
  int twins(int u, int v, GridPoint out[4]) const override;
  double sphereRadius() const override { return radius_; }
  Mapping mapping() const { return mapping_; }

  // Unit direction of grid vertex (u, v), computed at its canonical vertex, so that the grid
  // vertices of one point get bit-identical directions.
  Eigen::Vector3d direction(int u, int v) const;
  // The unit direction of square coordinates (x, y) in [-1, 1]^2.
  Eigen::Vector3d directionOfSquare(double x, double y) const;

 private:
  double radius_;
  Mapping mapping_;
};

}  // namespace ps::core
