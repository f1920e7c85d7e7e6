#pragma once
// A small copy of the heights around the tool, made on the editor thread and read by the haptic
// thread through a TripleBuffer: the haptic loop never touches the live Terrain, the editor never
// waits for the loop.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/chart.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/terrain.hpp"

namespace ps::haptics {

// The surface under a point (planet frame, planet metres).
struct SurfaceProbe {
  double depth = 0;  // below the surface along `up` (planet metres); negative above
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();      // outward radial direction at the foot point
  Eigen::Vector3d surface = Eigen::Vector3d::Zero();  // the foot point on the surface
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();       // grid coordinates of the foot point
};

// Heights of grid rows v0 .. v0+rows-1 and columns u0 .. u0+cols-1 (columns taken modulo m on a
// wrapping chart, so u0 may be negative; rows likewise across a torus's v seam). Next to a pole row
// the patch holds whole rows. On a chart that glues its sides beyond a seam (the octahedral chart's
// folds) a box that reaches a side also holds its images across it (Chart::gluedImages), so that a
// foot point across a fold from the tool (the inverse puts it on the other side of the square) is
// in the patch too. Reading is const, allocation-free and thread-compatible; capture() reuses its
// buffer.
//
// With a surface of its own over part of the grid (the sand TIN's region, a MeshPatch with a
// plane), the patch also holds that surface's triangles that reach within its radius of the
// tool, and the depth is taken under them where the foot point lies in one (the grid's heights
// there are what the TIN wrote back, sampled at the grid's spacing: an imprint narrower than a
// cell would be lost), under the grid elsewhere.
class TerrainPatch {
 public:
  // Copies the heights within `halfSize` grid cells (along v; along u widened by 1/cos(latitude)
  // on a sphere) of the point under `centre` (planet frame). Returns false (and leaves the patch
  // empty) when the point has no foot point on the chart.
  // `surface` (may be null; ignored without a plane): its triangles within the same reach go in
  // too. Editor thread; every buffer is reused.
  bool capture(const terrain::Terrain& terrain, const Eigen::Vector3d& centre, int halfSize,
               const terrain::MeshPatch* surface = nullptr);
  void clear() {
    valid_ = false;
    tris_.clear();
  }

  bool valid() const { return valid_; }
  const core::Chart* chart() const { return chart_; }
  std::uint64_t revision() const { return revision_; }
  // Process-unique number of the capture that filled this patch (0: never captured): the loop
  // notices a new snapshot by it.
  std::uint64_t serial() const { return serial_; }
  int u0() const { return u0_; }
  int v0() const { return v0_; }
  int cols() const { return cols_; }
  int rows() const { return rows_; }
  std::size_t capacity() const { return heights_.capacity(); }
  // The surface's triangles held (0: the grid alone).
  std::size_t surfaceTriangles() const { return tris_.size(); }

  // The boxes of grid vertices beyond the first one (the images across glued sides).
  int images() const { return images_; }

  // Bilinear height at grid coordinates (u, v); nullopt outside the patch.
  std::optional<double> heightAt(double u, double v) const;
  // The surface's height at (x, y) of its plane; nullopt outside every triangle held.
  std::optional<double> surfaceHeightAt(const Eigen::Vector2d& xy) const;
  // Where the foot point of `p` lies in the surface's plane; nullopt without a surface or
  // (sphere) on the far side of the planet.
  std::optional<Eigen::Vector2d> surfacePlanePoint(const Eigen::Vector3d& p) const;
  // Depth of `p` (planet frame) below the surface (the held triangles' where the foot point lies
  // in one, else the grid's bilinear one), radial on the chart; nullopt when the foot point is
  // outside the patch or p has none.
  std::optional<SurfaceProbe> probe(const Eigen::Vector3d& p) const;

 private:
  float at(int col, int row) const { return heights_[std::size_t(row) * cols_ + col]; }
  // An image box: its first vertex, size, and where its heights start in heights_.
  struct Image {
    int u0 = 0, v0 = 0, cols = 0, rows = 0;
    std::size_t offset = 0;
  };
  std::optional<double> heightInImage(const Image& b, double u, double v) const;

  const core::Chart* chart_ = nullptr;
  bool valid_ = false;
  std::uint64_t revision_ = 0, serial_ = 0;
  int u0_ = 0, v0_ = 0, cols_ = 0, rows_ = 0, m_ = 0;
  bool wraps_ = false, wrapsV_ = false;
  std::vector<float> heights_;
  Image image_[3];
  int images_ = 0;

  void captureSurface(const terrain::MeshPatch& surface, const Eigen::Vector3d& centre,
                      double reach);
  // A triangle of the surface, corners in its plane, counter-clockwise.
  struct Tri {
    double ax, ay, bx, by, cx, cy, ha, hb, hc;
  };
  terrain::MeshPatch::Plane plane_;
  std::vector<Tri> tris_;
  // Triangles by bucket of a uniform grid over their bounds (CSR: bucket b holds
  // bucketTris_[bucketStart_[b] .. bucketStart_[b + 1])), so that a tick tests a few.
  std::vector<std::uint32_t> bucketStart_, bucketTris_, bucketFill_;
  double bx0_ = 0, by0_ = 0, bucketSize_ = 1;
  int nbx_ = 0, nby_ = 0;
};

}  // namespace ps::haptics
