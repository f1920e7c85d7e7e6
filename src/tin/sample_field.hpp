#pragma once
// What a TIN approximates: heights on a W x H lattice of samples (the full resolution), the
// metric its error is measured in, and how much error each sample allows.
//
// Lattice coordinates: sample (i, j) sits at (x, y) = (i, j); j grows northwards (a flat chart's
// v, an image's rows counted from the bottom). A TIN's vertices live in these coordinates, at
// samples or (Steiner points, road points) between them.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/chart.hpp"

namespace ps::tin {

enum class ErrorMetric {
  kVertical,  // |sample height - the TIN's height above the same (x, y)|: flat terrains
  kChart3d,   // distance in R^3 from the sample's chart position to its triangle's: planets
};

struct SampleField {
  int width = 0, height = 0;
  std::span<const float> heights;  // metres, index = j * width + i
  ErrorMetric metric = ErrorMetric::kVertical;
  // kChart3d: the chart whose grid the lattice is, whole or the window of it whose first sample
  // is grid vertex (i0, j0) (a region of a planet): lattice sample (i, j) is grid vertex
  // (i + i0, j + j0), and heights hold the window's samples only. kVertical: unused.
  const core::Chart* chart = nullptr;
  int i0 = 0, j0 = 0;
  // Metres between samples along x and y (kVertical; output positions only, the vertical error
  // does not depend on them).
  double dx = 1.0, dy = 1.0;
  // The largest error each sample allows: uniformTolerance, or perSampleTolerance[j * width + i]
  // when that is not empty (a control map's).
  double uniformTolerance = 1.0;
  std::span<const float> perSampleTolerance;

  std::size_t index(int i, int j) const {
    return std::size_t(j) * std::size_t(width) + std::size_t(i);
  }
  float at(int i, int j) const { return heights[index(i, j)]; }
  double tolerance(std::size_t k) const {
    return perSampleTolerance.empty() ? uniformTolerance : double(perSampleTolerance[k]);
  }
  // The surface between samples: bilinear (what Steiner and road points take as their height).
  double heightAt(double x, double y) const;
  // Where the lattice point (x, y) with height h lies in the output's frame (metres): the flat
  // terrain's (x dx, y dy, h), or the chart's position.
  Eigen::Vector3d positionAt(double x, double y, double h) const;
  // kChart3d: the window's columns 0 and width - 1 are the seam's two sides (the whole grid's
  // width on a chart that wraps), and row j is a pole row of the grid.
  bool wrapsSeam() const;
  bool isPoleRow(int j) const;
  // kChart3d over the whole grid (no window): the chart's twins (seams, folded sides) and
  // canonical vertices are the TIN's, so that its welded mesh is closed where the chart is.
  bool wholeChart() const;
  // kChart3d: the positions of samples iFirst..iLast of row j (Chart::rowPositions).
  void rowPositions(int j, int iFirst, int iLast, core::Chart::RowOut out) const;
  Eigen::Vector3d samplePosition(int i, int j) const {
    return chart->position(i + i0, j + j0, double(at(i, j)));
  }

  // Throws core::InputError naming `what` when the sizes, spans or tolerances do not fit.
  void validate(const std::string& what) const;
};

}  // namespace ps::tin
