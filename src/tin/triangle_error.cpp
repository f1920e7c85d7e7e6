#include "tin/triangle_error.hpp"

#include <Eigen/Geometry>
#include <vector>

namespace ps::tin {

namespace {

template <class Measure>
void scan(const SampleField& field, const LatticeTriangle& t, WorstSample& worst,
          Measure&& measure) {
  forEachRowSpan(t, field.width, field.height, [&](int j, int i0, int i1) {
    worst.samples += i1 - i0 + 1;
    measure(j, i0, i1, [&](int i, double error) {
      const std::size_t k = field.index(i, j);
      const double ratio = error / field.tolerance(k);
      if (ratio > worst.ratio) worst = {ratio, error, std::int64_t(k), worst.samples};
    });
  });
}

}  // namespace

double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const double scale2 = std::max({ab.squaredNorm(), ac.squaredNorm(), (c - b).squaredNorm()});
  if (ab.cross(ac).squaredNorm() <= 1e-24 * scale2 * scale2) {
    return std::min({pointSegmentDistance(p, a, b), pointSegmentDistance(p, b, c),
                     pointSegmentDistance(p, c, a)});
  }
  // The closest point by Voronoi regions of the vertices, edges and face (Ericson, Real-Time
  // Collision Detection, 5.1.5).
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (p - (b + w * (c - b))).norm();
  }
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

WorstSample worstSample(const SampleField& field, const LatticeTriangle& t) {
  WorstSample worst;
  if (field.metric == ErrorMetric::kVertical) {
    // The triangle's plane h = c0 + cx x + cy y (a degenerate triangle covers no sample's
    // interior but may lie along a row: its samples are measured against its edges' heights).
    const Eigen::Vector2d e1 = t.xy[1] - t.xy[0], e2 = t.xy[2] - t.xy[0];
    const double det = e1.x() * e2.y() - e1.y() * e2.x();
    if (std::abs(det) < 1e-12) return worst;
    const double dh1 = t.h[1] - t.h[0], dh2 = t.h[2] - t.h[0];
    const double cx = (dh1 * e2.y() - dh2 * e1.y()) / det;
    const double cy = (dh2 * e1.x() - dh1 * e2.x()) / det;
    const double c0 = t.h[0] - cx * t.xy[0].x() - cy * t.xy[0].y();
    scan(field, t, worst, [&](int j, int i0, int i1, auto&& report) {
      const float* row = field.heights.data() + field.index(0, j);
      const double base = c0 + cy * j;
      for (int i = i0; i <= i1; ++i) report(i, std::abs(double(row[i]) - (base + cx * i)));
    });
    return worst;
  }
  const std::array<Eigen::Vector3d, 3> corner = {
      field.positionAt(t.xy[0].x(), t.xy[0].y(), t.h[0]),
      field.positionAt(t.xy[1].x(), t.xy[1].y(), t.h[1]),
      field.positionAt(t.xy[2].x(), t.xy[2].y(), t.h[2])};
  thread_local std::vector<double> xs, ys, zs;
  scan(field, t, worst, [&](int j, int i0, int i1, auto&& report) {
    const std::size_t n = std::size_t(i1 - i0 + 1);
    if (xs.size() < n) xs.resize(n), ys.resize(n), zs.resize(n);
    field.rowPositions(j, i0, i1, {xs.data(), ys.data(), zs.data()});
    for (int i = i0; i <= i1; ++i) {
      const std::size_t k = std::size_t(i - i0);
      report(i, pointTriangleDistance({xs[k], ys[k], zs[k]}, corner[0], corner[1], corner[2]));
    }
  });
  return worst;
}

}  // namespace ps::tin
