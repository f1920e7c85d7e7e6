#pragma once
// Greedy insertion into a CGAL triangulation (tin/cdt.hpp: include from .cpp files only), shared
// by the TIN mesher and the overlay's re-meshing around a stenciled track.
#include <cmath>
#include <cstdint>
#include <queue>
#include <vector>

#include "tin/cdt.hpp"
#include "tin/sample_field.hpp"
#include "tin/triangle_error.hpp"

namespace ps::tin {

inline double vertexHeight(const SampleField& field, const VertexHandle& v) {
  double& h = v->info().height;
  if (std::isnan(h)) h = field.heightAt(v->point().x(), v->point().y());
  return h;
}

inline LatticeTriangle latticeTriangle(const SampleField& field, const FaceHandle& f) {
  LatticeTriangle t;
  for (int k = 0; k < 3; ++k) {
    const Point& p = f->vertex(k)->point();
    t.xy[std::size_t(k)] = {p.x(), p.y()};
    t.h[std::size_t(k)] = vertexHeight(field, f->vertex(k));
  }
  return t;
}

// Lattice samples have integer coordinates: their in-circle test is exact in integer arithmetic,
// where EPICK's filtered predicates fall back to slow exact numbers on the degenerate (cocircular,
// collinear) cases a lattice is full of.
inline bool isLatticePoint(const Point& p) {
  constexpr double kLimit = 1 << 20;  // differences < 2^21: the in-circle terms stay < 2^86
  return p.x() == std::floor(p.x()) && p.y() == std::floor(p.y()) && std::abs(p.x()) < kLimit &&
         std::abs(p.y()) < kLimit;
}

// True when d lies strictly inside the circle through a, b, c (counter-clockwise).
inline bool strictlyInCircle(const Point& a, const Point& b, const Point& c, const Point& d) {
  if (!(isLatticePoint(a) && isLatticePoint(b) && isLatticePoint(c) && isLatticePoint(d)))
    return CGAL::side_of_oriented_circle(a, b, c, d) == CGAL::ON_POSITIVE_SIDE;
  __extension__ using Wide = __int128;
  const auto dx = [&](const Point& p) { return Wide(std::int64_t(p.x()) - std::int64_t(d.x())); };
  const auto dy = [&](const Point& p) { return Wide(std::int64_t(p.y()) - std::int64_t(d.y())); };
  const Wide ax = dx(a), ay = dy(a), bx = dx(b), by = dy(b), cx = dx(c), cy = dy(c);
  const Wide al = ax * ax + ay * ay, bl = bx * bx + by * by, cl = cx * cx + cy * cy;
  return ax * (by * cl - cy * bl) - ay * (bx * cl - cx * bl) + al * (bx * cy - cx * by) > 0;
}

// Greedy insertion: a max-heap of triangles over tolerance, each with its worst sample. An
// entry names its triangle by its three vertices (handles of vertices stay valid; faces do
// not), so an entry whose triangle was split since is recognised and dropped.
class GreedyInserter {
 public:
  GreedyInserter(Cdt& cdt, const SampleField& field) : cdt_(cdt), field_(field) {}

  void measureAll() {
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) measure(f);
  }

  void run() {
    const int m = field_.width - 1;
    const bool twins = field_.wrapsSeam();
    while (!queue_.empty()) {
      const Entry e = queue_.top();
      queue_.pop();
      FaceHandle f;
      if (!cdt_.is_face(e.a, e.b, e.c, f)) continue;
      const int i = int(e.sample % std::uint64_t(field_.width));
      const int j = int(e.sample / std::uint64_t(field_.width));
      insert(i, j, f);
      if (twins && (i == 0 || i == m)) insert(m - i, j, FaceHandle());
    }
  }

 private:
  struct Entry {
    double ratio;
    std::uint64_t sample;
    VertexHandle a, b, c;
    bool operator<(const Entry& o) const { return ratio < o.ratio; }
  };

  void measure(const FaceHandle& f) {
    const WorstSample w = worstSample(field_, latticeTriangle(field_, f));
    if (w.ratio > kWithinTolerance)
      queue_.push({w.ratio, std::uint64_t(w.sample), f->vertex(0), f->vertex(1), f->vertex(2)});
  }

  void insert(int i, int j, const FaceHandle& hint) {
    // Into the triangle (or onto the edge) without CGAL's Delaunay flips, then Lawson's flips
    // with a strict in-circle test, as Delatin does: where the new vertex and an old edge's far
    // side are cocircular (every rectangle of lattice samples is), the old edge stays. CGAL's
    // symbolic perturbation would take either; measured, keeping the old one needs fewer
    // vertices for the same error. The result is a Delaunay triangulation all the same.
    const VertexHandle v = cdt_.Cdt::Ctr::insert(Point(i, j), hint);
    v->info().height = field_.at(i, j);
    legalize(v);
    auto f = cdt_.incident_faces(v), done = f;
    do {
      if (!cdt_.is_infinite(f)) measure(f);
    } while (++f != done);
  }

  void legalize(const VertexHandle& v) {
    std::vector<FaceHandle> stack;
    auto fc = cdt_.incident_faces(v), done = fc;
    do stack.push_back(fc);
    while (++fc != done);
    while (!stack.empty()) {
      FaceHandle f = stack.back();
      stack.pop_back();
      if (cdt_.is_infinite(f) || !f->has_vertex(v)) continue;
      const int i = f->index(v);  // the edge opposite v
      if (f->is_constrained(i)) continue;
      FaceHandle g = f->neighbor(i);
      if (cdt_.is_infinite(g)) continue;
      const Point& w = g->vertex(cdt_.mirror_index(f, i))->point();
      if (!strictlyInCircle(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point(), w))
        continue;
      cdt_.flip(f, i);
      stack.push_back(f);
      stack.push_back(g);
    }
  }
  Cdt& cdt_;
  const SampleField& field_;
  std::priority_queue<Entry> queue_;
};

}  // namespace ps::tin
