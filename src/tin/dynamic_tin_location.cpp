#include <algorithm>
#include <cmath>
#include <vector>

#include "tin/dynamic_tin_impl.hpp"

// Where points lie in a DynamicTin: inside, how deep, on what height, near which vertex.

namespace ps::tin {

void DynamicTin::verticesWithin(const Eigen::Vector2d& centre, double radius,
                                std::vector<Vertex>& out) const {
  out.clear();
  std::vector<lean::FaceHandle> faces;
  impl_->facesTouching(centre, radius, faces);
  for (const lean::FaceHandle& f : faces)
    for (int k = 0; k < 3; ++k) {
      const lean::VertexHandle& v = f->vertex(k);
      if ((xyOf(v->point()) - centre).norm() <= radius) out.push_back(v->info().index);
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

bool DynamicTin::contains(const Eigen::Vector2d& p) const {
  lean::Cdt::Locate_type lt;
  int li = 0;
  impl_->cdt.locate(Point(p.x(), p.y()), lt, li, impl_->startFace());
  return lt != lean::Cdt::OUTSIDE_CONVEX_HULL && lt != lean::Cdt::OUTSIDE_AFFINE_HULL;
}

double DynamicTin::depthInside(const Eigen::Vector2d& p) const {
  const lean::Cdt& cdt = impl_->cdt;
  double nearest = INFINITY;
  auto c = cdt.incident_vertices(cdt.infinite_vertex()), done = c;
  do {
    auto next = c;
    ++next;
    nearest = std::min(nearest, pointSegmentDistance(p, xyOf(c->point()), xyOf(next->point())));
  } while (++c != done);
  return contains(p) ? nearest : -nearest;
}

std::vector<std::uint8_t> DynamicTin::deeperThan(std::span<const Eigen::Vector2d> points,
                                                 double depth) const {
  const lean::Cdt& cdt = impl_->cdt;
  std::vector<std::uint8_t> out(points.size(), 0);
  if (points.empty() || cdt.dimension() < 2 || !(depth > 0.0)) {
    for (std::size_t i = 0; i < points.size(); ++i) out[i] = depthInside(points[i]) >= depth;
    return out;
  }
  // The border's edges, and a grid of cells over its box grown by `depth`: an edge closer than
  // `depth` to p has p within `depth` of its box, so it is listed in p's cell.
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> edges;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
  auto c = cdt.incident_vertices(cdt.infinite_vertex()), done = c;
  do {
    auto next = c;
    ++next;
    edges.emplace_back(xyOf(c->point()), xyOf(next->point()));
    lo = lo.cwiseMin(edges.back().first);
    hi = hi.cwiseMax(edges.back().first);
  } while (++c != done);
  lo.array() -= depth;
  hi.array() += depth;
  const double cell = std::max(depth, (hi - lo).maxCoeff() / 1024.0);  // at most 1024^2 cells
  const int nx = std::max(1, int(std::ceil((hi.x() - lo.x()) / cell)));
  const int ny = std::max(1, int(std::ceil((hi.y() - lo.y()) / cell)));
  auto cellOf = [&](double v, double origin, int n) {
    return std::clamp(int(std::floor((v - origin) / cell)), 0, n - 1);
  };
  std::vector<std::vector<std::uint32_t>> bucket(std::size_t(nx) * std::size_t(ny));
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto& [a, b] = edges[e];
    const int x0 = cellOf(std::min(a.x(), b.x()) - depth, lo.x(), nx);
    const int x1 = cellOf(std::max(a.x(), b.x()) + depth, lo.x(), nx);
    const int y0 = cellOf(std::min(a.y(), b.y()) - depth, lo.y(), ny);
    const int y1 = cellOf(std::max(a.y(), b.y()) + depth, lo.y(), ny);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) bucket[std::size_t(y) * nx + x].push_back(std::uint32_t(e));
    }
  }
  lean::FaceHandle walk = impl_->startFace();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d& p = points[i];
    if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;  // outside
    bool near = false;
    for (std::uint32_t e :
         bucket[std::size_t(cellOf(p.y(), lo.y(), ny)) * nx + cellOf(p.x(), lo.x(), nx)]) {
      if (pointSegmentDistance(p, edges[e].first, edges[e].second) < depth) {
        near = true;
        break;
      }
    }
    if (near) continue;
    lean::Cdt::Locate_type lt;
    int li = 0;
    const lean::FaceHandle f = cdt.locate(Point(p.x(), p.y()), lt, li, walk);
    const bool inside =
        lt != lean::Cdt::OUTSIDE_CONVEX_HULL && lt != lean::Cdt::OUTSIDE_AFFINE_HULL;
    if (inside) walk = f;
    out[i] = inside;
  }
  return out;
}

double DynamicTin::heightAt(const Eigen::Vector2d& p) const {
  lean::Cdt::Locate_type lt;
  int li = 0;
  const lean::FaceHandle f = impl_->cdt.locate(Point(p.x(), p.y()), lt, li, impl_->startFace());
  if (lt == lean::Cdt::OUTSIDE_CONVEX_HULL || lt == lean::Cdt::OUTSIDE_AFFINE_HULL) return NAN;
  impl_->hint = f->vertex(0);
  if (lt == lean::Cdt::VERTEX) return f->vertex(li)->info().height;
  const Point q(p.x(), p.y());
  const Point &a = f->vertex(0)->point(), &b = f->vertex(1)->point(), &c = f->vertex(2)->point();
  const double area = signedArea2(a, b, c);
  const double l0 = signedArea2(q, b, c) / area, l1 = signedArea2(a, q, c) / area;
  return l0 * f->vertex(0)->info().height + l1 * f->vertex(1)->info().height +
         (1.0 - l0 - l1) * f->vertex(2)->info().height;
}

DynamicTin::Vertex DynamicTin::vertexNear(const Eigen::Vector2d& p, double radius) const {
  const lean::FaceHandle f = impl_->cdt.locate(Point(p.x(), p.y()), impl_->startFace());
  Vertex best = kNoVertex;
  double nearest = radius;
  const auto consider = [&](const lean::FaceHandle& g) {
    for (int k = 0; k < 3; ++k) {
      const lean::VertexHandle& v = g->vertex(k);
      if (impl_->cdt.is_infinite(v)) continue;
      const double d = (xyOf(v->point()) - p).norm();
      if (d <= nearest) nearest = d, best = v->info().index;
    }
  };
  consider(f);
  for (int k = 0; k < 3; ++k) consider(f->neighbor(k));
  return best;
}

}  // namespace ps::tin
