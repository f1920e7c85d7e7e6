#pragma once
// Which triangles of a triangle soup hold a point: a bucket grid over the triangles' bounding
// boxes and barycentric tests. Independent of CGAL's point location on purpose: the checks use
// it to verify what the triangulation built, and the overlay to test a road's footprint.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace ps::tin {

class TinLocator {
 public:
  // Buckets of `bucket` x `bucket` units over [0, width) x [0, height) (points outside are
  // clamped into the border buckets).
  TinLocator(const std::vector<Eigen::Vector2d>& xy,
             const std::vector<std::array<std::uint32_t, 3>>& triangles, double width,
             double height, double bucket = 8.0);

  struct Hit {
    std::uint32_t triangle;
    double l0, l1, l2;  // barycentric coordinates of the point
  };
  // Calls f(hit) for every non-degenerate triangle holding p (its closed area, with `slack` of
  // barycentric tolerance): none, one, or several on shared edges and vertices.
  template <class F>
  void visit(const Eigen::Vector2d& p, F&& f, double slack = 1e-9) const {
    for (const std::uint32_t t : bucket_[bucketOf(p)]) {
      const auto& tri = (*triangles_)[t];
      const Eigen::Vector2d &a = (*xy_)[tri[0]], &b = (*xy_)[tri[1]], &c = (*xy_)[tri[2]];
      const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
      if (area == 0) continue;
      const double l0 = ((b - p).x() * (c - p).y() - (b - p).y() * (c - p).x()) / area;
      const double l1 = ((c - p).x() * (a - p).y() - (c - p).y() * (a - p).x()) / area;
      const double l2 = 1.0 - l0 - l1;
      if (l0 < -slack || l1 < -slack || l2 < -slack) continue;
      f(Hit{t, l0, l1, l2});
    }
  }
  bool contains(const Eigen::Vector2d& p, double slack = 1e-9) const {
    bool any = false;
    visit(
        p, [&](const Hit&) { any = true; }, slack);
    return any;
  }

 private:
  std::size_t bucketOf(const Eigen::Vector2d& p) const;
  const std::vector<Eigen::Vector2d>* xy_;
  const std::vector<std::array<std::uint32_t, 3>>* triangles_;
  double size_;
  int bw_, bh_;
  std::vector<std::vector<std::uint32_t>> bucket_;
};

}  // namespace ps::tin
