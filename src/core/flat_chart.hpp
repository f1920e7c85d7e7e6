#pragma once
#include "core/chart.hpp"

namespace ps::core {

// A flat heightmap (a terrain tile, paper 001's setting): grid vertex (u, v) sits at
// (u * dx, v * dy) in the plane z = 0 and a height displaces it along +z:
//   position = (u * dx, v * dy, h),   up = (0, 0, 1).
// No seam (wrapsU() is false), no pole rows, sphereRadius() is 0. Triangles that are CCW in (u, v)
// face +z. When a flat chart comes from an image, row 0 of the image is v = m (north up).
class FlatChart final : public Chart {
 public:
  // dx, dy: metres between neighbouring grid vertices along u and v. Throws InputError for a
  // non-positive or non-finite spacing.
  FlatChart(GridSize grid, double dx, double dy);

  std::string name() const override { return "flat"; }
  Eigen::Vector3d position(int u, int v, double h) const override {
    return {double(u) * dx_, double(v) * dy_, h};
  }
  void rowPositions(int v, int uFirst, int uLast, const float* hRow, RowOut out) const override {
    double* __restrict x = out.x;
    double* __restrict y = out.y;
    double* __restrict z = out.z;
    const double yv = double(v) * dy_;
    for (int u = uFirst; u <= uLast; ++u) {
      const int k = u - uFirst;
      x[k] = double(u) * dx_, y[k] = yv, z[k] = double(hRow[u]);
    }
  }
  Eigen::Vector3d up(int, int) const override { return Eigen::Vector3d::UnitZ(); }
  Eigen::Vector3d positionAt(double u, double v, double h) const override {
    return {u * dx_, v * dy_, h};
  }
  // The grid point straight below p, clamped to the grid.
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override;
  bool wrapsU() const override { return false; }
  bool hasPoleRows() const override { return false; }
  double sphereRadius() const override { return 0.0; }

  // Heights are refused (and edits saturate) beyond +-kHeightLimit metres: a flat chart has no
  // radius to take a quarter of, so it names its own limit.
  static constexpr double kHeightLimit = 1.0e6;
  double heightLimit() const override { return kHeightLimit; }

  double dx() const { return dx_; }
  double dy() const { return dy_; }

 private:
  double dx_, dy_;
};

}  // namespace ps::core
