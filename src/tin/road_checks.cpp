#include "tin/road_checks.hpp"

#include <algorithm>
#include <cmath>

#include "core/input_error.hpp"
#include "tin/cdt.hpp"

namespace ps::tin {

double signedArea(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

std::set<std::pair<std::uint32_t, std::uint32_t>> edgesOf(
    const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  return edges;
}

void refuseDegenerateTriangles(const Road& t) {
  for (std::size_t k = 0; k < t.triangles.size(); ++k) {
    const auto& tri = t.triangles[k];
    for (const auto v : tri)
      if (v >= t.xy.size() || v >= t.h.size())
        throw core::InputError("road triangle " + std::to_string(k + 1) + " names vertex " +
                               std::to_string(v + 1) + " of " + std::to_string(t.xy.size()));
    if (std::abs(signedArea(t.xy[tri[0]], t.xy[tri[1]], t.xy[tri[2]])) < 1e-12)
      throw core::InputError("road triangle " + std::to_string(k + 1) +
                             " is degenerate (its corners are collinear or repeated)");
  }
}

void refuseSelfIntersection(const Road& t, const TinLocator& footprint,
                            const std::string& areaUnit) {
  Cdt cdt;
  std::vector<VertexHandle> v;
  for (const auto& p : t.xy) v.push_back(cdt.insert(Point(p.x(), p.y())));
  const std::size_t distinct = cdt.number_of_vertices();
  for (const auto& [a, b] : edgesOf(t.triangles)) cdt.insert_constraint(v[a], v[b]);
  if (cdt.number_of_vertices() != distinct)
    throw core::InputError(
        "the road crosses itself: " + std::to_string(cdt.number_of_vertices() - distinct) +
        " points where its edges cross (seen from above)");
  double roadArea = 0, covered = 0;
  for (const auto& tri : t.triangles)
    roadArea += std::abs(signedArea(t.xy[tri[0]], t.xy[tri[1]], t.xy[tri[2]]));
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    const Eigen::Vector2d a(f->vertex(0)->point().x(), f->vertex(0)->point().y());
    const Eigen::Vector2d b(f->vertex(1)->point().x(), f->vertex(1)->point().y());
    const Eigen::Vector2d c(f->vertex(2)->point().x(), f->vertex(2)->point().y());
    if (footprint.contains((a + b + c) / 3.0, 0.0)) covered += std::abs(signedArea(a, b, c));
  }
  if (roadArea > covered * (1 + 1e-9) + 1e-12)
    throw core::InputError("the road overlaps itself: its triangles cover " +
                           core::exactNumber(roadArea) + " " + areaUnit + " but only " +
                           core::exactNumber(covered) + " of ground");
}

}  // namespace ps::tin
