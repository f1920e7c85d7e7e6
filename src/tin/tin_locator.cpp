#include "tin/tin_locator.hpp"

#include <algorithm>
#include <cmath>

namespace ps::tin {

TinLocator::TinLocator(const std::vector<Eigen::Vector2d>& xy,
                       const std::vector<std::array<std::uint32_t, 3>>& triangles, double width,
                       double height, double bucket)
    : xy_(&xy),
      triangles_(&triangles),
      size_(bucket),
      bw_(std::max(1, int(std::ceil(width / bucket)))),
      bh_(std::max(1, int(std::ceil(height / bucket)))),
      bucket_(std::size_t(bw_) * std::size_t(bh_)) {
  auto cell = [&](double x, int n) { return std::clamp(int(std::floor(x / size_)), 0, n - 1); };
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const auto v : triangles[t]) {
      x0 = std::min(x0, xy[v].x()), x1 = std::max(x1, xy[v].x());
      y0 = std::min(y0, xy[v].y()), y1 = std::max(y1, xy[v].y());
    }
    for (int by = cell(y0 - 1e-6, bh_); by <= cell(y1 + 1e-6, bh_); ++by)
      for (int bx = cell(x0 - 1e-6, bw_); bx <= cell(x1 + 1e-6, bw_); ++bx)
        bucket_[std::size_t(by) * std::size_t(bw_) + std::size_t(bx)].push_back(std::uint32_t(t));
  }
}

std::size_t TinLocator::bucketOf(const Eigen::Vector2d& p) const {
  const int bx = std::clamp(int(std::floor(p.x() / size_)), 0, bw_ - 1);
  const int by = std::clamp(int(std::floor(p.y() / size_)), 0, bh_ - 1);
  return std::size_t(by) * std::size_t(bw_) + std::size_t(bx);
}

}  // namespace ps::tin
