#include "tin/tin_check.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "tin/tin_locator.hpp"
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
  const TinLocator locator(xy, tin.triangles, field.width, field.height);

  TinErrorCheck out;
  for (int j = 0; j < field.height; ++j) {
    for (int i = 0; i < field.width; ++i) {
      const std::size_t k = field.index(i, j);
      double best = INFINITY;  // a sample on an edge belongs to both sides: the smaller error
      locator.visit({i, j}, [&](const TinLocator::Hit& hit) {
        const auto& tri = tin.triangles[hit.triangle];
        double error;
        if (field.metric == ErrorMetric::kVertical) {
          error = std::abs(double(field.heights[k]) -
                           planeHeight(corner[tri[0]], corner[tri[1]], corner[tri[2]],
                                       {i * field.dx, j * field.dy}, hit.l0, hit.l1, hit.l2));
        } else {
          error = pointTriangleDistance(field.samplePosition(i, j), corner[tri[0]], corner[tri[1]],
                                        corner[tri[2]]);
        }
        best = std::min(best, error);
      });
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

std::pair<double, double> weldKey(const SampleField& field, double x, double y) {
  // One surface point, one key: a chart's seam twins and pole rows meet at u = 0.
  const double m = field.width - 1, top = field.height - 1;
  if (field.wholeChart() && x == std::floor(x) && y == std::floor(y)) {
    // A grid point: the chart's canonical vertex of its surface point (a folded side's mirror, a
    // corner, a seam's twin, a pole row).
    const core::GridPoint c = field.chart->canonical(int(x), int(y));
    x = c.u, y = c.v;
  } else if (field.wholeChart()) {
    // A point between grid points on a glued side (a quality TIN's Steiner point, inserted with
    // its twins): one key for the twins, as the chart's gluing pairs them.
    const core::Gluing gl = field.chart->gluing();
    if (gl.vSides == core::SideGluing::kSeam && y == top) y = 0;
    if (gl.vSides == core::SideGluing::kMirror && (y == 0 || y == top)) x = std::min(x, m - x);
    if (gl.uSides == core::SideGluing::kMirror && (x == 0 || x == m)) y = std::min(y, top - y);
  }
  if ((field.isPoleRow(0) && y == 0) || (field.isPoleRow(field.height - 1) && y == top)) x = 0;
  if (field.wrapsSeam() && x == m) x = 0;
  return {x, y};
}

WeldedMesh weldTin(const SampleField& field, const Tin& tin) {
  std::map<std::pair<double, double>, std::uint32_t> key;
  WeldedMesh out;
  out.vertexOf.resize(tin.xy.size());
  for (std::size_t v = 0; v < tin.xy.size(); ++v) {
    const auto [it, fresh] =
        key.emplace(weldKey(field, tin.xy[v].x(), tin.xy[v].y()), std::uint32_t(key.size()));
    out.vertexOf[v] = it->second;
  }
  out.vertices = key.size();
  for (std::size_t k = 0; k < tin.triangles.size(); ++k) {
    const auto& t = tin.triangles[k];
    const std::array<std::uint32_t, 3> w = {out.vertexOf[t[0]], out.vertexOf[t[1]],
                                            out.vertexOf[t[2]]};
    if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) {
      ++out.collapsed;
      continue;
    }
    out.triangles.push_back(w);
    out.sourceTriangle.push_back(std::uint32_t(k));
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
