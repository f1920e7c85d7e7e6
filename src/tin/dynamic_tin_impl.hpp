#pragma once
// DynamicTin's state (internal to src/tin): the CDT, the vertex numbers and the constrained
// edges' generations, shared by dynamic_tin.cpp (building and changing the TIN) and
// dynamic_tin_location.cpp (where points lie in it).
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "tin/cdt.hpp"
#include "tin/dynamic_tin.hpp"
#include "tin/triangle_error.hpp"

namespace ps::tin {

inline constexpr std::uint32_t kUnnumbered = ~std::uint32_t(0);

inline std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

inline double signedArea2(const Point& a, const Point& b, const Point& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// The volume under one face: its area times its mean height.
inline double faceVolume(const lean::FaceHandle& f) {
  const Point &a = f->vertex(0)->point(), &b = f->vertex(1)->point(), &c = f->vertex(2)->point();
  return 0.5 * signedArea2(a, b, c) *
         (f->vertex(0)->info().height + f->vertex(1)->info().height + f->vertex(2)->info().height) /
         3.0;
}

inline Eigen::Vector2d xyOf(const Point& p) {
  return {p.x(), p.y()};
}

struct DynamicTin::Impl {
  lean::Cdt cdt;
  std::vector<lean::VertexHandle> handles;  // by vertex number; null for a free number
  std::vector<Vertex> freeNumbers;
  std::unordered_map<std::uint64_t, std::uint32_t> generations;  // constrained edges
  mutable lean::VertexHandle hint;  // a live vertex near the last operation
  std::uint64_t epoch = 0;          // counts changes of the triangulation

  Vertex number(const lean::VertexHandle& v) {
    if (v->info().index != kUnnumbered) return v->info().index;
    Vertex id;
    if (!freeNumbers.empty()) {
      id = freeNumbers.back();
      freeNumbers.pop_back();
      handles[id] = v;
    } else {
      id = Vertex(handles.size());
      handles.push_back(v);
    }
    v->info().index = id;
    return id;
  }

  const lean::VertexHandle& handle(Vertex v) const {
    if (v >= handles.size() || handles[v] == lean::VertexHandle())
      throw std::out_of_range("DynamicTin: vertex " + std::to_string(v) + " does not exist");
    return handles[v];
  }

  // Where point location starts walking: a live vertex, the last one an operation touched.
  lean::FaceHandle startFace() const { return hint->face(); }

  // The finite faces that come within `radius` of `centre`, by walking across edges from the
  // face there (a disc is convex: the faces it touches are connected).
  void facesTouching(const Eigen::Vector2d& centre, double radius,
                     std::vector<lean::FaceHandle>& out) const {
    out.clear();
    const lean::FaceHandle start = cdt.locate(Point(centre.x(), centre.y()), startFace());
    if (cdt.is_infinite(start)) return;
    std::vector<lean::FaceHandle> stack{start};
    std::unordered_set<const void*> seen;
    while (!stack.empty()) {
      const lean::FaceHandle f = stack.back();
      stack.pop_back();
      if (cdt.is_infinite(f) || !seen.insert(&*f).second) continue;
      if (!touches(f, centre, radius)) continue;
      out.push_back(f);
      for (int k = 0; k < 3; ++k) stack.push_back(f->neighbor(k));
    }
  }

  static bool touches(const lean::FaceHandle& f, const Eigen::Vector2d& c, double radius) {
    const Eigen::Vector2d a = xyOf(f->vertex(0)->point()), b = xyOf(f->vertex(1)->point()),
                          d = xyOf(f->vertex(2)->point());
    const auto side = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
      return (q - p).x() * (c - p).y() - (q - p).y() * (c - p).x();
    };
    if (side(a, b) >= 0 && side(b, d) >= 0 && side(d, a) >= 0) return true;
    return std::min({pointSegmentDistance(c, a, b), pointSegmentDistance(c, b, d),
                     pointSegmentDistance(c, d, a)}) <= radius;
  }

  // Tags the constrained path from a to b (split at the vertices on it, crossings included,
  // which lie on it only to rounding) with `generation`: from each vertex, the constrained edge
  // that gets closest to b.
  void tagPath(const lean::VertexHandle& a, const lean::VertexHandle& b, std::uint32_t generation) {
    lean::VertexHandle at = a;
    const Eigen::Vector2d target = xyOf(b->point());
    for (std::size_t guard = 0; at != b && guard <= handles.size(); ++guard) {
      lean::VertexHandle next;
      double best = (xyOf(at->point()) - target).norm();
      auto f = cdt.incident_faces(at), done = f;
      do {
        const int i = f->index(at);
        if (!f->is_constrained(lean::Cdt::cw(i))) continue;  // the edge from at to vertex ccw(i)
        const lean::VertexHandle u = f->vertex(lean::Cdt::ccw(i));
        if (cdt.is_infinite(u)) continue;
        const double d = (xyOf(u->point()) - target).norm();
        if (d < best) best = d, next = u;
      } while (++f != done);
      if (next == lean::VertexHandle()) break;
      generations[edgeKey(number(at), number(next))] = generation;
      at = next;
    }
  }
};

}  // namespace ps::tin
