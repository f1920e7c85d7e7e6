#include "tin/strip.hpp"

#include <algorithm>
#include <cmath>

#include "core/input_error.hpp"

namespace ps::tin {

Strip stripAlong(const std::vector<Eigen::Vector2d>& centre, double width) {
  if (!(std::isfinite(width) && width > 0))
    throw core::InputError("strip width " + core::exactNumber(width) + " must be positive");
  std::vector<Eigen::Vector2d> p;
  for (const auto& c : centre)
    if (p.empty() || (c - p.back()).norm() > 1e-9 * width) p.push_back(c);
  if (p.size() < 2) throw core::InputError("a strip needs a path of at least two distinct points");
  Strip s;
  const double half = 0.5 * width;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Eigen::Vector2d in = (p[k] - p[k == 0 ? 0 : k - 1]).normalized();
    const Eigen::Vector2d out = (p[std::min(k + 1, p.size() - 1)] - p[k]).normalized();
    const Eigen::Vector2d dirIn = k == 0 ? out : in, dirOut = k + 1 == p.size() ? in : out;
    Eigen::Vector2d normal(-(dirIn + dirOut).y(), (dirIn + dirOut).x());
    if (normal.norm() < 1e-12) normal = Eigen::Vector2d(-dirIn.y(), dirIn.x());  // a U-turn
    normal.normalize();
    // The mitre: half / cos(half the turn), at most 2 x half.
    const double cosHalfTurn = std::max(0.5, normal.dot(Eigen::Vector2d(-dirIn.y(), dirIn.x())));
    const double offset = half / cosHalfTurn;
    s.xy.push_back(p[k] + offset * normal);
    s.xy.push_back(p[k] - offset * normal);
    if (k > 0) {
      const auto l0 = std::uint32_t(2 * k - 2), r0 = l0 + 1, l1 = l0 + 2, r1 = l0 + 3;
      s.triangles.push_back({l0, r0, r1});
      s.triangles.push_back({l0, r1, l1});
    }
  }
  return s;
}

}  // namespace ps::tin
