#include "core/flat_chart.hpp"

#include <algorithm>
#include <cmath>

#include "core/input_error.hpp"

namespace ps::core {

FlatChart::FlatChart(GridSize grid, double dx, double dy) : Chart(grid), dx_(dx), dy_(dy) {
  for (const double d : {dx, dy}) {
    if (!std::isfinite(d) || d <= 0.0) {
      throw InputError("flat chart grid spacing " + std::to_string(d) +
                       " m must be positive and finite");
    }
  }
}

std::optional<Eigen::Vector2d> FlatChart::inverse(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) return std::nullopt;
  const double m = grid().m();
  return Eigen::Vector2d(std::clamp(p.x() / dx_, 0.0, m), std::clamp(p.y() / dy_, 0.0, m));
}

}  // namespace ps::core
