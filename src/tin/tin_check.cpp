#include "tin/tin_check.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "tin/triangle_error.hpp"

namespace ps::tin {

namespace {

// The height of the plane through a, b, c above p (metres); where the three are the lattice's
// own corners, that is the barycentric blend l0 a + l1 b + l2 c the locator found.
double planeHeight(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector2d& p, double l0, double l1, double l2) {
  const Eigen::Vector2d e1 = (b - a).head<2>(), e2 = (c - a).head<2>(), d = p - a.head<2>();
  const double det = e1.x() * e2.y() - e1.y() * e2.x();
  if (det == 0) return l0 * a.z() + l1 * b.z() + l2 * c.z();
  const double s = (d.x() * e2.y() - d.y() * e2.x()) / det;
  const double t = (e1.x() * d.y() - e1.y() * d.x()) / det;
  return a.z() + s * (b.z() - a.z()) + t * (c.z() - a.z());
}

}  // namespace

TinErrorCheck measureTinError(const SampleField& field, const Tin& tin,
                              std::span<const Eigen::Vector3d> written) {
  // Samples are located among the triangles in lattice coordinates; the error is that of the
  // corners as written (a rounded corner moves its triangle's plane, and the plane is evaluated
  // where the sample truly is).
  const bool rounded = written.size() == tin.xy.size();
  const std::vector<Eigen::Vector2d>& xy = tin.xy;
  std::vector<Eigen::Vector3d> corner(tin.xy.size());
  for (std::size_t v = 0; v < tin.xy.size(); ++v)
    corner[v] = rounded ? written[v] : field.positionAt(tin.xy[v].x(), tin.xy[v].y(), tin.h[v]);
  // Buckets of about 8 x 8 samples, each listing the triangles whose bounding box touches it.
  constexpr int kBucket = 8;
  const int bw = (field.width + kBucket - 1) / kBucket, bh = (field.height + kBucket - 1) / kBucket;
  std::vector<std::vector<std::uint32_t>> bucket(std::size_t(bw) * std::size_t(bh));
  for (std::size_t t = 0; t < tin.triangles.size(); ++t) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const auto v : tin.triangles[t]) {
      x0 = std::min(x0, xy[v].x()), x1 = std::max(x1, xy[v].x());
      y0 = std::min(y0, xy[v].y()), y1 = std::max(y1, xy[v].y());
    }
    const int bx0 = std::clamp(int(std::floor(x0 - 1e-6)) / kBucket, 0, bw - 1);
    const int bx1 = std::clamp(int(std::floor(x1 + 1e-6)) / kBucket, 0, bw - 1);
    const int by0 = std::clamp(int(std::floor(y0 - 1e-6)) / kBucket, 0, bh - 1);
    const int by1 = std::clamp(int(std::floor(y1 + 1e-6)) / kBucket, 0, bh - 1);
    for (int by = by0; by <= by1; ++by)
      for (int bx = bx0; bx <= bx1; ++bx)
        bucket[std::size_t(by) * std::size_t(bw) + std::size_t(bx)].push_back(std::uint32_t(t));
  }

  TinErrorCheck out;
  for (int j = 0; j < field.height; ++j) {
    for (int i = 0; i < field.width; ++i) {
      const std::size_t k = field.index(i, j);
      const Eigen::Vector2d p(i, j);
      double best = INFINITY;  // a sample on an edge belongs to both sides: the smaller error
      for (const auto t :
           bucket[std::size_t(j / kBucket) * std::size_t(bw) + std::size_t(i / kBucket)]) {
        const auto& tri = tin.triangles[t];
        const Eigen::Vector2d &a = xy[tri[0]], &b = xy[tri[1]], &c = xy[tri[2]];
        const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
        if (area == 0) continue;
        const double l0 = ((b - p).x() * (c - p).y() - (b - p).y() * (c - p).x()) / area;
        const double l1 = ((c - p).x() * (a - p).y() - (c - p).y() * (a - p).x()) / area;
        const double l2 = 1.0 - l0 - l1;
        constexpr double kOn = -1e-9;
        if (l0 < kOn || l1 < kOn || l2 < kOn) continue;
        double error;
        if (field.metric == ErrorMetric::kVertical) {
          error = std::abs(double(field.heights[k]) -
                           planeHeight(corner[tri[0]], corner[tri[1]], corner[tri[2]],
                                       {i * field.dx, j * field.dy}, l0, l1, l2));
        } else {
          error = pointTriangleDistance(field.chart->position(i, j, field.heights[k]),
                                        corner[tri[0]], corner[tri[1]], corner[tri[2]]);
        }
        best = std::min(best, error);
      }
      ++out.samples;
      if (!std::isfinite(best)) {
        ++out.uncovered;
        continue;
      }
      const double ratio = best / field.tolerance(k);
      out.maxError = std::max(out.maxError, best);
      if (ratio > out.maxRatio) out.maxRatio = ratio, out.worstSample = std::int64_t(k);
    }
  }
  return out;
}

WeldedMesh weldTin(const SampleField& field, const Tin& tin) {
  // One surface point, one key: a chart's seam twins and pole rows meet at u = 0.
  const double m = field.width - 1;
  const bool chart = field.metric == ErrorMetric::kChart3d;
  const bool poles = chart && field.chart->hasPoleRows(), seam = chart && field.chart->wrapsU();
  std::map<std::pair<double, double>, std::uint32_t> key;
  WeldedMesh out;
  out.vertexOf.resize(tin.xy.size());
  for (std::size_t v = 0; v < tin.xy.size(); ++v) {
    double x = tin.xy[v].x(), y = tin.xy[v].y();
    if (poles && (y == 0 || y == m)) x = 0;
    if (seam && x == m) x = 0;
    const auto [it, fresh] = key.emplace(std::pair(x, y), std::uint32_t(key.size()));
    out.vertexOf[v] = it->second;
  }
  out.vertices = key.size();
  for (const auto& t : tin.triangles) {
    const std::array<std::uint32_t, 3> w = {out.vertexOf[t[0]], out.vertexOf[t[1]],
                                            out.vertexOf[t[2]]};
    if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) {
      ++out.collapsed;
      continue;
    }
    out.triangles.push_back(w);
  }
  return out;
}

MeshTopology meshTopology(std::size_t vertexCount,
                          const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  MeshTopology top;
  top.vertices = vertexCount;
  top.triangles = triangles.size();
  // Per undirected edge: how often it is used, and the sum of its directions (+1 a->b, -1 b->a):
  // a manifold, consistently oriented interior edge is used twice with opposite directions.
  std::unordered_map<std::uint64_t, std::pair<int, int>> edge;
  edge.reserve(triangles.size() * 2);
  for (const auto& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) ++top.degenerate;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      auto& [uses, direction] = edge[key];
      ++uses;
      direction += a < b ? 1 : -1;
    }
  }
  top.edges = edge.size();
  for (const auto& [key, use] : edge) {
    if (use.first == 1)
      ++top.borderEdges;
    else if (use.first > 2 || use.second != 0)
      ++top.nonManifoldEdges;
  }
  return top;
}

}  // namespace ps::tin
