#include "tin/scattered_tin.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "core/input_error.hpp"
#include "tin/sample_field.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::tin {

std::vector<std::size_t> convexHull(std::span<const Eigen::Vector3d> points) {
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return points[a].x() != points[b].x() ? points[a].x() < points[b].x()
                                          : points[a].y() < points[b].y();
  });
  const auto cross = [&](std::size_t o, std::size_t a, std::size_t b) {
    const Eigen::Vector3d &p = points[o], &q = points[a], &r = points[b];
    return (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
  };
  std::vector<std::size_t> hull(2 * order.size() + 1);
  std::size_t k = 0;
  for (const std::size_t i : order) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], i) <= 0) --k;
    hull[k++] = i;
  }
  for (std::size_t j = order.size() - 1, lower = k + 1; j-- > 0;) {  // upper chain
    const std::size_t i = order[j];
    while (k >= lower && cross(hull[k - 2], hull[k - 1], i) <= 0) --k;
    hull[k++] = i;
  }
  hull.resize(k > 1 ? k - 1 : k);  // the last point is the first again
  return hull;
}

DynamicTin errorBoundedTin(std::span<const Eigen::Vector3d> points, double spacing,
                           double tolerance, ScatteredTinReport* reportOut) {
  if (!(std::isfinite(spacing) && spacing > 0))
    throw core::InputError("error-bounded TIN: spacing " + core::exactNumber(spacing) +
                           " must be positive and finite");
  if (!(std::isfinite(tolerance) && tolerance > 0))
    throw core::InputError("error-bounded TIN: tolerance " + core::exactNumber(tolerance) +
                           " m must be positive and finite");
  ScatteredTinReport report;
  report.points = points.size();
  const DynamicTin all(points);  // throws for too few or non-finite points

  // 2. The all-points surface on a lattice over the bounding box, meshed by the export's
  // generation.
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (const Eigen::Vector3d& p : points) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  const int W = std::max(2, int(std::ceil((hi.x() - lo.x()) / spacing)) + 1);
  const int H = std::max(2, int(std::ceil((hi.y() - lo.y()) / spacing)) + 1);
  if (double(W) * double(H) > double(1 << 26))
    throw core::InputError("error-bounded TIN: a lattice of " + std::to_string(W) + " x " +
                           std::to_string(H) + " samples is too large");
  report.latticeSamples = std::size_t(W) * std::size_t(H);
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  std::vector<float> lattice(report.latticeSamples);
  double mean = 0;
  for (const Eigen::Vector3d& p : points) mean += p.z() / double(points.size());
  for (int j = 0; j < H; ++j) {
    for (int i = 0; i < W; ++i) {
      const Eigen::Vector2d p = lo + spacing * Eigen::Vector2d(i, j);
      double h = all.heightAt(p);
      // Outside the hull: the surface where the line to the centre enters it (what the lattice
      // holds there only steers which vertices the greedy pass picks near the border).
      for (int step = 1; std::isnan(h) && step <= 64; ++step)
        h = all.heightAt(p + (centre - p) * (step / 64.0));
      lattice[std::size_t(j) * std::size_t(W) + std::size_t(i)] = float(std::isnan(h) ? mean : h);
    }
  }
  SampleField field;
  field.width = W;
  field.height = H;
  field.heights = lattice;
  field.metric = ErrorMetric::kVertical;
  field.dx = field.dy = spacing;
  field.uniformTolerance = tolerance;
  TinOptions options;
  options.removeRedundant = true;
  const Tin greedy = buildTin(field, options);
  report.latticeVertices = greedy.xy.size();

  // 3. The hull's points and the lattice vertices well inside it.
  std::vector<Eigen::Vector3d> start;
  for (const std::size_t k : convexHull(points)) start.push_back(points[k]);
  report.hullVertices = start.size();
  std::vector<Eigen::Vector2d> lattice2d;
  lattice2d.reserve(greedy.xy.size());
  for (const Eigen::Vector2d& ij : greedy.xy) lattice2d.push_back(lo + spacing * ij);
  const std::vector<std::uint8_t> deep = all.deeperThan(lattice2d, 0.5 * spacing);
  for (std::size_t k = 0; k < lattice2d.size(); ++k) {
    const Eigen::Vector2d& p = lattice2d[k];
    if (deep[k]) start.emplace_back(p.x(), p.y(), all.heightAt(p));
  }
  DynamicTin tin(start);
  report.startVertices = tin.vertexCount();

  // 4. Every point within tolerance: the worst first, each measured again before it goes in (an
  // earlier insertion nearby may have brought it within).
  std::vector<std::pair<double, std::size_t>> over;
  for (;;) {
    over.clear();
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double e = std::abs(points[k].z() - tin.heightAt(points[k].head<2>()));
      // NaN: a point on the hull's border that rounding puts outside (it spans the border).
      if (e > tolerance) over.emplace_back(e, k);
    }
    if (over.empty()) break;
    ++report.repairRounds;
    std::sort(over.begin(), over.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    for (const auto& [e, k] : over) {
      const Eigen::Vector2d p = points[k].head<2>();
      if (std::abs(points[k].z() - tin.heightAt(p)) <= tolerance) continue;
      tin.insert(p, points[k].z());
      ++report.repaired;
    }
  }
  for (const Eigen::Vector3d& p : points)
    report.maxError = std::max(report.maxError, std::abs(p.z() - tin.heightAt(p.head<2>())));
  report.vertices = tin.vertexCount();
  if (reportOut) *reportOut = report;
  return tin;
}

}  // namespace ps::tin
