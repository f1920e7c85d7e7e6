#include "tin/strip.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"

namespace ps::tin {

Strip stripAlong(const std::vector<Eigen::Vector2d>& centre, double width) {
  if (!(std::isfinite(width) && width > 0))
    throw core::InputError("strip width " + core::exactNumber(width) + " must be positive");
  // The path simplified (Douglas-Peucker) to within the width: a tracked stroke jitters by more
  // than a road turns, and its zigzags would fold the strip over itself.
  std::vector<Eigen::Vector2d> dedup;
  for (const auto& c : centre)
    if (dedup.empty() || (c - dedup.back()).norm() > 1e-9 * width) dedup.push_back(c);
  std::vector<bool> keep(dedup.size(), false);
  if (!dedup.empty()) keep.front() = keep.back() = true;
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  if (dedup.size() > 2) spans.push_back({0, dedup.size() - 1});
  while (!spans.empty()) {
    const auto [first, last] = spans.back();
    spans.pop_back();
    const Eigen::Vector2d a = dedup[first], d = dedup[last] - a;
    double worst = -1;
    std::size_t at = first;
    for (std::size_t k = first + 1; k < last; ++k) {
      const Eigen::Vector2d q = dedup[k] - a;
      const double len2 = d.squaredNorm();
      const double s = len2 > 0 ? std::clamp(q.dot(d) / len2, 0.0, 1.0) : 0.0;
      const double off = (q - s * d).norm();
      if (off > worst) worst = off, at = k;
    }
    if (worst > width) {
      keep[at] = true;
      if (at - first > 1) spans.push_back({first, at});
      if (last - at > 1) spans.push_back({at, last});
    }
  }
  std::vector<Eigen::Vector2d> p;
  for (std::size_t k = 0; k < dedup.size(); ++k)
    if (keep[k]) p.push_back(dedup[k]);
  // A stroke that doubles back (scrubbing over a ridge) has no strip: drop the points where the
  // path turns by more than 100 degrees, the sharpest first, until none is left.
  for (;;) {
    std::size_t sharpest = 0;
    double lowest = std::cos(100.0 * std::numbers::pi / 180.0);
    for (std::size_t k = 1; k + 1 < p.size(); ++k) {
      const double turn = (p[k] - p[k - 1]).normalized().dot((p[k + 1] - p[k]).normalized());
      if (turn < lowest) lowest = turn, sharpest = k;
    }
    if (sharpest == 0) break;
    p.erase(p.begin() + std::ptrdiff_t(sharpest));
    // Out and back to the same point (a grid-snapped stroke's jitter) leaves it twice in a row.
    if ((p[sharpest] - p[sharpest - 1]).norm() <= 1e-9 * width)
      p.erase(p.begin() + std::ptrdiff_t(sharpest == p.size() - 1 ? sharpest - 1 : sharpest));
  }
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
