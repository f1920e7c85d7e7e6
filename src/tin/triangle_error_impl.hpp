#pragma once
// The row walk of tin/triangle_error.hpp (a template: the inner loops inline into each metric).
#include <algorithm>
#include <cmath>

namespace ps::tin {

template <class F>
void forEachRowSpan(const LatticeTriangle& t, int width, int height, F&& f) {
  constexpr double kSlack = 1e-9;
  const auto& p = t.xy;
  const double yLo = std::min({p[0].y(), p[1].y(), p[2].y()});
  const double yHi = std::max({p[0].y(), p[1].y(), p[2].y()});
  const int jFirst = std::max(0, int(std::ceil(yLo - kSlack)));
  const int jLast = std::min(height - 1, int(std::floor(yHi + kSlack)));
  for (int j = jFirst; j <= jLast; ++j) {
    const double y = j;
    double xLo = INFINITY, xHi = -INFINITY;
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector2d& a = p[e];
      const Eigen::Vector2d& b = p[(e + 1) % 3];
      const double ya = a.y(), yb = b.y();
      if (std::min(ya, yb) - kSlack > y || std::max(ya, yb) + kSlack < y) continue;
      if (std::abs(yb - ya) <= kSlack) {  // an edge along the row
        xLo = std::min({xLo, a.x(), b.x()});
        xHi = std::max({xHi, a.x(), b.x()});
        continue;
      }
      const double s = std::clamp((y - ya) / (yb - ya), 0.0, 1.0);
      const double x = a.x() + s * (b.x() - a.x());
      xLo = std::min(xLo, x);
      xHi = std::max(xHi, x);
    }
    if (!(xLo <= xHi)) continue;
    const int iFirst = std::max(0, int(std::ceil(xLo - kSlack)));
    const int iLast = std::min(width - 1, int(std::floor(xHi + kSlack)));
    if (iFirst <= iLast) f(j, iFirst, iLast);
  }
}

}  // namespace ps::tin
