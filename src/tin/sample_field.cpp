#include "tin/sample_field.hpp"

#include <algorithm>
#include <cmath>

#include "core/input_error.hpp"

namespace ps::tin {

double SampleField::heightAt(double x, double y) const {
  const double cx = std::clamp(x, 0.0, double(width - 1)),
               cy = std::clamp(y, 0.0, double(height - 1));
  const int i0 = std::min(int(cx), std::max(width - 2, 0)),
            j0 = std::min(int(cy), std::max(height - 2, 0));
  const int i1 = std::min(i0 + 1, width - 1), j1 = std::min(j0 + 1, height - 1);
  const double fx = cx - i0, fy = cy - j0;
  const double south = (1 - fx) * at(i0, j0) + fx * at(i1, j0);
  const double north = (1 - fx) * at(i0, j1) + fx * at(i1, j1);
  return (1 - fy) * south + fy * north;
}

Eigen::Vector3d SampleField::positionAt(double x, double y, double h) const {
  if (metric == ErrorMetric::kChart3d) return chart->positionAt(x + i0, y + j0, h);
  return {x * dx, y * dy, h};
}

bool SampleField::wrapsSeam() const {
  return metric == ErrorMetric::kChart3d && chart->wrapsU() && i0 == 0 &&
         width == chart->grid().side();
}

bool SampleField::wholeChart() const {
  return metric == ErrorMetric::kChart3d && i0 == 0 && j0 == 0 && width == chart->grid().side() &&
         height == chart->grid().side();
}

bool SampleField::isPoleRow(int j) const {
  if (metric != ErrorMetric::kChart3d || !chart->hasPoleRows()) return false;
  const int v = j + j0;
  return v == 0 || v == chart->grid().m();
}

void SampleField::rowPositions(int j, int iFirst, int iLast, core::Chart::RowOut out) const {
  if (i0 == 0) {  // the window's rows start where the grid's do
    chart->rowPositions(j + j0, iFirst, iLast, heights.data() + index(0, j), out);
    return;
  }
  // The chart reads hRow[u] for the grid's u = iFirst + i0 .. iLast + i0: the window's row copied
  // to where the chart looks for it.
  thread_local std::vector<float> row;
  const std::size_t first = std::size_t(iFirst + i0), n = std::size_t(iLast - iFirst + 1);
  if (row.size() < first + n) row.resize(first + n);
  std::copy_n(heights.data() + index(iFirst, j), n, row.data() + first);
  chart->rowPositions(j + j0, iFirst + i0, iLast + i0, row.data(), out);
}

void SampleField::validate(const std::string& what) const {
  if (width < 2 || height < 2)
    throw core::InputError(what + ": a TIN needs at least 2 x 2 samples (got " +
                           std::to_string(width) + " x " + std::to_string(height) + ")");
  const std::size_t n = std::size_t(width) * std::size_t(height);
  if (heights.size() != n)
    throw core::InputError(what + ": " + std::to_string(heights.size()) + " heights for " +
                           std::to_string(width) + " x " + std::to_string(height) + " samples");
  if (!perSampleTolerance.empty() && perSampleTolerance.size() != n)
    throw core::InputError(what + ": the control map has " +
                           std::to_string(perSampleTolerance.size()) + " values for " +
                           std::to_string(n) + " samples");
  if (perSampleTolerance.empty() && !(std::isfinite(uniformTolerance) && uniformTolerance > 0))
    throw core::InputError(what + ": the maximum error " + core::exactNumber(uniformTolerance) +
                           " m must be positive and finite");
  for (const float t : perSampleTolerance)
    if (!(std::isfinite(t) && t > 0))
      throw core::InputError(what + ": every sample's allowed error must be positive and finite (" +
                             core::exactNumber(t) + " m found)");
  if (metric == ErrorMetric::kChart3d) {
    if (!chart) throw core::InputError(what + ": the 3D error needs the planet's chart");
    const int side = chart->grid().side();
    if (i0 < 0 || j0 < 0 || i0 + width > side || j0 + height > side)
      throw core::InputError(what + ": the samples' window " + std::to_string(width) + "x" +
                             std::to_string(height) + " at (" + std::to_string(i0) + ", " +
                             std::to_string(j0) + ") is not inside the chart's " +
                             std::to_string(side) + "^2 grid");
  } else if (!(std::isfinite(dx) && dx > 0 && std::isfinite(dy) && dy > 0)) {
    throw core::InputError(what + ": sample spacing " + core::exactNumber(dx) + " x " +
                           core::exactNumber(dy) + " m must be positive and finite");
  }
}

}  // namespace ps::tin
