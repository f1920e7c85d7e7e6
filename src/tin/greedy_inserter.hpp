#pragma once
// Greedy insertion into a CGAL triangulation (tin/cdt.hpp: include from .cpp files only), shared
// by the TIN mesher and the overlay's re-meshing around a stenciled road.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <queue>
#include <utility>
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

// The in-circle determinant's sign for a, b, c (counter-clockwise) given relative to d, in an
// integer type wide enough for its terms: 1 when d lies inside the circle, 0 on it, -1 outside.
template <class Int>
int inCircleSign(Int ax, Int ay, Int bx, Int by, Int cx, Int cy) {
  const Int al = ax * ax + ay * ay, bl = bx * bx + by * by, cl = cx * cx + cy * cy;
  const Int v = ax * (by * cl - cy * bl) - ay * (bx * cl - cx * bl) + al * (bx * cy - cx * by);
  return v > 0 ? 1 : v < 0 ? -1 : 0;
}

// Where d lies against the circle through a, b, c (counter-clockwise): 1 inside, 0 on it, -1
// outside.
inline int inCircle(const Point& a, const Point& b, const Point& c, const Point& d) {
  if (!(isLatticePoint(a) && isLatticePoint(b) && isLatticePoint(c) && isLatticePoint(d)))
    return int(CGAL::side_of_oriented_circle(a, b, c, d));
  const auto det = [&](auto zero) {
    using Int = decltype(zero);
    const auto dx = [&](const Point& p) { return Int(std::int64_t(p.x()) - std::int64_t(d.x())); };
    const auto dy = [&](const Point& p) { return Int(std::int64_t(p.y()) - std::int64_t(d.y())); };
    return inCircleSign<Int>(dx(a), dy(a), dx(b), dy(b), dx(c), dy(c));
  };
  // Points within 2^15 of d (a vertex's neighbours, nearly always): every term stays < 2^61,
  // so 64-bit integers are exact.
  constexpr double kNear = 1 << 15;
  const auto near = [&](const Point& p) {
    return std::abs(p.x() - d.x()) < kNear && std::abs(p.y() - d.y()) < kNear;
  };
  if (near(a) && near(b) && near(c)) return det(std::int64_t(0));
  __extension__ using Wide = __int128;
  return det(Wide(0));
}

inline bool strictlyInCircle(const Point& a, const Point& b, const Point& c, const Point& d) {
  return inCircle(a, b, c, d) > 0;
}

// Greedy insertion: a max-heap of triangles over tolerance, each with its worst sample. An
// entry names its face and the face's three vertices in order: insertion and flips rewrite
// faces in place (and never free one), so an entry whose face no longer has those vertices was
// split or flipped since and is dropped. That test is far cheaper than looking the triangle up
// by its vertices (CGAL's is_face). It needs vertex handles that are not reused while entries
// are queued: no vertex is removed while the queue holds entries (removeRedundant empties the
// queue before each removal).
class GreedyInserter {
 public:
  GreedyInserter(Cdt& cdt, const SampleField& field) : cdt_(cdt), field_(field) {}

  void measureAll() {
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) measure(f);
  }

  // Greedy insertion keeps every vertex it inserts, though vertices inserted later around one
  // often carry the surface there on their own. Tries removing each lattice vertex off the
  // lattice's border (which holds the seam twins and the corners) with no constraint at it;
  // keeps the removal where every sample of the re-triangulated hole stays within tolerance,
  // and puts the vertex back otherwise (repairing at once, by greedy insertion, any triangle
  // then over tolerance: where points are cocircular the put-back vertex may join
  // differently). Returns the vertices removed.
  std::size_t removeRedundant() {
    const int m = field_.width - 1, n = field_.height - 1;
    std::vector<VertexHandle> candidates;
    for (auto v = cdt_.finite_vertices_begin(); v != cdt_.finite_vertices_end(); ++v) {
      const Point& p = v->point();
      if (p.x() > 0 && p.y() > 0 && p.x() < m && p.y() < n && isLatticePoint(p))
        candidates.push_back(v);
    }
    // In rows: neighbouring candidates share faces, which then are still in the cache.
    std::sort(candidates.begin(), candidates.end(),
              [](const VertexHandle& a, const VertexHandle& b) {
                return a->point().y() != b->point().y() ? a->point().y() < b->point().y()
                                                        : a->point().x() < b->point().x();
              });
    std::size_t removed = 0;
    std::vector<std::pair<VertexHandle, VertexHandle>> rim;
    std::vector<FaceHandle> hole, stack;
    for (const VertexHandle& v : candidates) {
      if (!gatherLink(v)) continue;
      // Most vertices are needed: find that out on the hole's own Delaunay triangulation
      // before touching the CDT (removing and putting back costs several times more).
      const Fill fill = fillWithinTolerance();
      if (fill == Fill::kOver) continue;
      const Point p = v->point();
      cdt_.remove(v);
      if (fill == Fill::kWithin) {
        ++removed;
        continue;
      }
      // Cocircular link vertices: CGAL may have chosen other diagonals than the check did.
      rim.clear();
      for (std::size_t k = 0; k < link_.size(); ++k)
        rim.emplace_back(link_[k].v, link_[(k + 1) % link_.size()].v);
      const FaceHandle over = cdt_.locate(p, link_.front().v->face());
      if (holeWithinTolerance(over, rim, hole, stack)) {
        ++removed;
        continue;
      }
      // Put back, v may leave a face of the failed fill in place where it is cocircular with
      // it: measure around the whole former star, and repair now, before any queue entry could
      // name a vertex that a later removal deletes.
      measureAround(place(int(p.x()), int(p.y()), over));
      for (const LinkVertex& u : link_) measureAround(u.v);
      run();
    }
    return removed;
  }

  void run() {
    const int m = field_.width - 1, n = field_.height - 1;
    const bool twins = field_.wrapsSeam(), wholeChart = field_.wholeChart();
    while (!queue_.empty()) {
      const Entry e = queue_.top();
      queue_.pop();
      const FaceHandle f = e.face;
      if (!cdt_.tds().faces().is_used(f) || f->vertex(0) != e.a || f->vertex(1) != e.b ||
          f->vertex(2) != e.c)
        continue;
      const int i = int(e.sample % std::uint64_t(field_.width));
      const int j = int(e.sample / std::uint64_t(field_.width));
      insert(i, j, f);
      if (wholeChart && (i == 0 || i == m || j == 0 || j == n)) {
        // A side's vertex with its twins (a seam's, a folded side's mirror, a corner's three):
        // both sides then carry the same vertices, and the welded mesh is closed across them.
        core::GridPoint twin[4];
        const int count = field_.chart->twins(i, j, twin);
        for (int k = 1; k < count; ++k)
          if (twin[k].u != i || twin[k].v != j) insert(twin[k].u, twin[k].v, FaceHandle());
      } else if (twins && (i == 0 || i == m)) {
        insert(m - i, j, FaceHandle());
      }
    }
  }

 private:
  struct Entry {
    double ratio;
    std::uint64_t sample;
    FaceHandle face;
    VertexHandle a, b, c;
    bool operator<(const Entry& o) const { return ratio < o.ratio; }
  };

  void measure(const FaceHandle& f) {
    const WorstSample w = worstSample(field_, latticeTriangle(field_, f));
    if (w.ratio > kWithinTolerance)
      queue_.push({w.ratio, std::uint64_t(w.sample), f, f->vertex(0), f->vertex(1), f->vertex(2)});
  }

  enum class Fill { kOver, kWithin, kWithinTied };

  // A neighbour of a vertex considered for removal, relative to it (small integers).
  struct LinkVertex {
    VertexHandle v;
    std::int64_t x, y;
  };

  // v's neighbours, counter-clockwise, into link_. False where v cannot be removed here: a
  // constrained edge at it, or a neighbour that is infinite, off the lattice or far away.
  bool gatherLink(const VertexHandle& v) {
    constexpr double kNear = 1 << 15;  // keeps inCircleNear's terms below 2^61
    link_.clear();
    const Point& p = v->point();
    auto f = cdt_.incident_faces(v), done = f;
    do {
      const int i = f->index(v);
      if (f->is_constrained(Cdt::cw(i))) return false;  // the edge from v to the next neighbour
      const VertexHandle u = f->vertex(Cdt::ccw(i));
      if (cdt_.is_infinite(u)) return false;
      const double dx = u->point().x() - p.x(), dy = u->point().y() - p.y();
      if (!isLatticePoint(u->point()) || std::abs(dx) >= kNear || std::abs(dy) >= kNear)
        return false;
      link_.push_back({u, std::int64_t(dx), std::int64_t(dy)});
    } while (++f != done);
    return link_.size() >= 3;
  }

  // In-circle and orientation on link vertices, exact in 64-bit integers.
  static int inCircleNear(const LinkVertex& a, const LinkVertex& b, const LinkVertex& c,
                          const LinkVertex& d) {
    return inCircleSign<std::int64_t>(a.x - d.x, a.y - d.y, b.x - d.x, b.y - d.y, c.x - d.x,
                                      c.y - d.y);
  }
  static std::int64_t turn(const LinkVertex& a, const LinkVertex& b, std::int64_t x,
                           std::int64_t y) {
    return (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x);
  }

  // The Delaunay triangulation of the star-shaped hole that removing the vertex whose link is
  // link_ would leave, by clipping ears whose circumcircle holds no link vertex (such an ear is
  // a triangle of the link's Delaunay triangulation, which fills the hole), and whether every
  // sample under it is within tolerance. kWithinTied: within, but an ear was cocircular with
  // another link vertex, so the CDT may fill the hole differently.
  Fill fillWithinTolerance() {
    const std::size_t n = link_.size();
    polygon_.resize(n);
    for (std::size_t q = 0; q < n; ++q) polygon_[q] = q;
    ears_.clear();
    bool tied = false;
    while (polygon_.size() >= 3) {
      const std::size_t k = polygon_.size();
      std::size_t ear = k;
      for (std::size_t e = 0; e < k && ear == k; ++e) {
        const std::size_t ia = polygon_[e], ib = polygon_[(e + 1) % k], ic = polygon_[(e + 2) % k];
        const LinkVertex &a = link_[ia], &b = link_[ib], &c = link_[ic];
        if (k > 3 && turn(a, b, c.x, c.y) <= 0) continue;
        bool empty = true, onCircle = false;
        for (std::size_t q = 0; q < n && empty; ++q) {
          if (q == ia || q == ib || q == ic) continue;
          const int side = inCircleNear(a, b, c, link_[q]);
          empty = side <= 0;
          onCircle = onCircle || side == 0;
        }
        if (!empty) continue;
        ear = e;
        tied = tied || onCircle;
        ears_.push_back({ia, ib, ic});
      }
      if (ear == k) return Fill::kOver;  // no ear found (not expected): keep the vertex
      polygon_.erase(polygon_.begin() + std::ptrdiff_t((ear + 1) % k));
    }
    // The removed vertex (the origin) was inserted for its own error: the ear over it is the
    // likeliest to fail, so it is measured first.
    for (std::size_t q = 0; q < ears_.size(); ++q) {
      const LinkVertex &a = link_[ears_[q][0]], &b = link_[ears_[q][1]], &c = link_[ears_[q][2]];
      if (turn(a, b, 0, 0) >= 0 && turn(b, c, 0, 0) >= 0 && turn(c, a, 0, 0) >= 0) {
        std::swap(ears_[0], ears_[q]);
        break;
      }
    }
    for (const auto& t : ears_) {
      LatticeTriangle lt;
      for (std::size_t q = 0; q < 3; ++q) {
        const VertexHandle& u = link_[t[q]].v;
        lt.xy[q] = {u->point().x(), u->point().y()};
        lt.h[q] = vertexHeight(field_, u);
      }
      if (worstSample(field_, lt).ratio > kWithinTolerance) return Fill::kOver;
    }
    return tied ? Fill::kWithinTied : Fill::kWithin;
  }

  // The faces that filled the hole left by a removed vertex: those reached from `start` (the
  // face over the removed point) without crossing the hole's rim. True when every sample they
  // cover is within tolerance.
  bool holeWithinTolerance(const FaceHandle& start,
                           const std::vector<std::pair<VertexHandle, VertexHandle>>& rim,
                           std::vector<FaceHandle>& hole, std::vector<FaceHandle>& stack) {
    const auto onRim = [&](const VertexHandle& a, const VertexHandle& b) {
      return std::any_of(rim.begin(), rim.end(), [&](const auto& e) {
        return (e.first == a && e.second == b) || (e.first == b && e.second == a);
      });
    };
    hole.clear();
    stack.assign(1, start);
    while (!stack.empty()) {
      const FaceHandle f = stack.back();
      stack.pop_back();
      if (std::find(hole.begin(), hole.end(), f) != hole.end()) continue;
      hole.push_back(f);
      if (cdt_.is_infinite(f) ||
          worstSample(field_, latticeTriangle(field_, f)).ratio > kWithinTolerance)
        return false;
      for (int k = 0; k < 3; ++k)
        if (!onRim(f->vertex(Cdt::ccw(k)), f->vertex(Cdt::cw(k)))) stack.push_back(f->neighbor(k));
    }
    return true;
  }

  void insert(int i, int j, const FaceHandle& hint) {
    // Into the triangle (or onto the edge) without CGAL's Delaunay flips, then Lawson's flips
    // with a strict in-circle test, as Delatin does: where the new vertex and an old edge's far
    // side are cocircular (every rectangle of lattice samples is), the old edge stays. CGAL's
    // symbolic perturbation would take either; measured, keeping the old one needs fewer
    // vertices for the same error. The result is a Delaunay triangulation all the same.
    measureAround(place(i, j, hint));
  }

  VertexHandle place(int i, int j, const FaceHandle& hint) {
    const VertexHandle v = cdt_.Cdt::Ctr::insert(Point(i, j), hint);
    v->info().height = field_.at(i, j);
    legalize(v);
    return v;
  }

  void measureAround(const VertexHandle& v) {
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
  // removeRedundant's scratch: a vertex's neighbours, the hole's rim as it is clipped, and the
  // triangles that fill it.
  std::vector<LinkVertex> link_;
  std::vector<std::size_t> polygon_;
  std::vector<std::array<std::size_t, 3>> ears_;
};

}  // namespace ps::tin
