#pragma once
// Greedy insertion into a CGAL triangulation (tin/cdt.hpp: include from .cpp files only), shared
// by the TIN mesher and the overlay's re-meshing around a stenciled track.
#include <cmath>
#include <cstdint>
#include <queue>

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

// Lattice samples have integer coordinates: their in-circle and orientation tests are exact in
// integer arithmetic, where EPICK's filtered predicates fall back to slow exact numbers on the
// degenerate (cocircular, collinear) cases a lattice is full of.
inline bool isLatticePoint(const Point& p) {
  constexpr double kLimit = 1 << 20;  // differences < 2^21: the in-circle terms stay < 2^86
  return p.x() == std::floor(p.x()) && p.y() == std::floor(p.y()) && std::abs(p.x()) < kLimit &&
         std::abs(p.y()) < kLimit;
}

inline bool cocircular(const Point& a, const Point& b, const Point& c, const Point& d) {
  if (!(isLatticePoint(a) && isLatticePoint(b) && isLatticePoint(c) && isLatticePoint(d)))
    return CGAL::side_of_oriented_circle(a, b, c, d) == CGAL::ON_ORIENTED_BOUNDARY;
  __extension__ using Wide = __int128;
  const auto dx = [&](const Point& p) { return Wide(std::int64_t(p.x()) - std::int64_t(d.x())); };
  const auto dy = [&](const Point& p) { return Wide(std::int64_t(p.y()) - std::int64_t(d.y())); };
  const Wide ax = dx(a), ay = dy(a), bx = dx(b), by = dy(b), cx = dx(c), cy = dy(c);
  const Wide al = ax * ax + ay * ay, bl = bx * bx + by * by, cl = cx * cx + cy * cy;
  return ax * (by * cl - cy * bl) - ay * (bx * cl - cx * bl) + al * (bx * cy - cx * by) == 0;
}

inline CGAL::Orientation orientationOf(const Point& a, const Point& b, const Point& c) {
  if (!(isLatticePoint(a) && isLatticePoint(b) && isLatticePoint(c)))
    return CGAL::orientation(a, b, c);
  const std::int64_t d =
      (std::int64_t(b.x()) - std::int64_t(a.x())) * (std::int64_t(c.y()) - std::int64_t(a.y())) -
      (std::int64_t(b.y()) - std::int64_t(a.y())) * (std::int64_t(c.x()) - std::int64_t(a.x()));
  return d > 0 ? CGAL::LEFT_TURN : d < 0 ? CGAL::RIGHT_TURN : CGAL::COLLINEAR;
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
    const VertexHandle v = cdt_.insert(Point(i, j), hint);
    v->info().height = field_.at(i, j);
    keepOldDiagonals(v);
    auto f = cdt_.incident_faces(v), done = f;
    do {
      if (!cdt_.is_infinite(f)) measure(f);
    } while (++f != done);
  }

  // Where the new vertex v and an old edge's far side are cocircular (on a sample lattice every
  // rectangle of samples is), either diagonal is Delaunay; CGAL's symbolic perturbation may
  // have taken the one to v. Put the old edge back, as an insertion by flips with a strict
  // in-circle test (Delatin's) keeps it: measured, that needs fewer vertices for the same error.
  void keepOldDiagonals(const VertexHandle& v) {
    for (bool flipped = true; flipped;) {
      flipped = false;
      auto fc = cdt_.incident_faces(v), done = fc;
      do {
        FaceHandle f = fc;
        if (cdt_.is_infinite(f)) continue;
        const int iv = f->index(v), i = cdt_.ccw(iv);  // edge i: v to w = vertex cw(iv)
        if (f->is_constrained(i)) continue;
        const FaceHandle g = f->neighbor(i);
        if (cdt_.is_infinite(g)) continue;
        const Point& a = f->vertex(i)->point();
        const Point& b = g->vertex(cdt_.mirror_index(f, i))->point();
        const Point& w = f->vertex(cdt_.cw(iv))->point();
        if (!cocircular(v->point(), w, a, b)) continue;
        const CGAL::Orientation sv = orientationOf(a, b, v->point()), sw = orientationOf(a, b, w);
        if (sv == sw || sv == CGAL::COLLINEAR || sw == CGAL::COLLINEAR)
          continue;  // not a convex quadrilateral: the old edge cannot come back
        cdt_.flip(f, i);
        for (int k = 0; k < 3; ++k)
          if (!cdt_.is_infinite(f->neighbor(k))) measure(f->neighbor(k));
        if (!cdt_.is_infinite(f)) measure(f);
        flipped = true;
        break;
      } while (++fc != done);
    }
  }

  Cdt& cdt_;
  const SampleField& field_;
  std::priority_queue<Entry> queue_;
};

}  // namespace ps::tin
