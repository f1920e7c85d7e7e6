#include "sand/stroke_tin.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_set>

#include "core/flat_chart.hpp"
#include "edit/control_vertex.hpp"
#include "sand/displacement.hpp"

namespace ps::sand {

TangentFrame::TangentFrame(const core::Chart& chart, core::GridPoint at)
    : origin(chart.position(at.u, at.v, 0.0)), up(chart.up(at.u, at.v)) {
  const Eigen::Vector3d across =
      std::abs(up.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  east = across.cross(up).normalized();
  north = up.cross(east);
}

namespace {

// The smallest spacing between grid points at the equator (lat-long: a meridian step) or on a
// flat grid.
double smallestSpacing(const core::Chart& chart) {
  if (chart.sphereRadius() > 0) return std::numbers::pi * chart.sphereRadius() / chart.grid().m();
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(&chart))
    return std::min(flat->dx(), flat->dy());
  return largestSpacing(chart);
}

}  // namespace

StrokeTin::StrokeTin(const core::Chart& chart, std::span<const float> heights,
                     const edit::Region& F, core::GridPoint centre, double tolerance,
                     const TinSandSettings& sand)
    : chart_(&chart), footprint_(F), frame_(chart, centre) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const bool sphere = chart.sphereRadius() > 0;
  // Every distinct point of the region (a pole row once, the seam's u = m as its twin u = 0).
  F.forEachSpan([&](int v, int ub, int ue) {
    for (int u = ub; u <= ue; ++u) {
      if (sphere && (u == m || ((v == 0 || v == m) && u != 0))) continue;
      points_.push_back({u, v, frame_.project(chart.position(u, v, 0.0))});
      left_.push_back(heights[g.index(u, v)]);
    }
  });
  // The TIN's points: at most one per cell of the chart's smallest spacing at the equator, so
  // that the pole's crowded rows (thousands of points a few metres apart on a lat-long chart)
  // do not crowd the TIN too; everywhere else that is every point.
  const double cell = 0.99 * smallestSpacing(chart);
  std::unordered_set<std::uint64_t> taken;
  std::vector<Eigen::Vector3d> xyz;
  candidate_.assign(points_.size(), 0);
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const Eigen::Vector2d& p = points_[k].xy;
    const auto ix = std::int64_t(std::floor(p.x() / cell)) + (1 << 30);
    const auto iy = std::int64_t(std::floor(p.y() / cell)) + (1 << 30);
    if (taken.insert((std::uint64_t(ix) << 32) | std::uint64_t(iy)).second) {
      xyz.emplace_back(p.x(), p.y(), double(left_[k]));
      candidate_[k] = 1;
    }
  }
  vertex_.assign(points_.size(), tolerance > 0 ? 0 : 1);
  startVertices_ = xyz.size();
  if (tolerance > 0) {
    sand_.emplace(tin::errorBoundedTin(xyz, smallestSpacing(chart), tolerance, &generation_), sand);
  } else {
    sand_.emplace(tin::DynamicTin(xyz), sand);
    generation_.points = generation_.vertices = xyz.size();
  }
  // The surface under every point (its own height where it is a vertex): each point takes the
  // change of the surface, so a point the TIN left out, or one within the tolerance of it,
  // keeps its own detail.
  surface_.resize(points_.size());
  for (std::size_t k = 0; k < points_.size(); ++k)
    surface_[k] = sand_->tin().heightAt(points_[k].xy);
}

std::size_t StrokeTin::densify(const Eigen::Vector2d& centre, double radius) {
  std::size_t added = 0;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    if (vertex_[k] || !candidate_[k] || (points_[k].xy - centre).squaredNorm() > radius * radius)
      continue;
    vertex_[k] = 1;
    // A point on the domain's border to rounding stays out (heightAt says NaN there).
    if (std::isnan(sand_->tin().heightAt(points_[k].xy))) continue;
    sand_->insert(points_[k].xy, double(left_[k]));
    ++added;
  }
  if (added)
    for (std::size_t k = 0; k < points_.size(); ++k)
      surface_[k] = sand_->tin().heightAt(points_[k].xy);
  return added;
}

terrain::MeshPatch StrokeTin::patch(double marginCells) const {
  terrain::MeshPatch p;
  const tin::Tin t = sand_->tin().toTin();
  const double R = chart_->sphereRadius();
  const core::GridSize g = chart_->grid();
  p.positions.reserve(t.xy.size());
  p.plane.emplace();
  p.plane->origin = frame_.origin;
  p.plane->east = frame_.east;
  p.plane->north = frame_.north;
  p.plane->up = frame_.up;
  p.plane->radius = R > 0 ? R : 0.0;
  p.xy.assign(t.xy.begin(), t.xy.end());
  for (std::size_t i = 0; i < t.xy.size(); ++i) {
    const double x = t.xy[i].x(), y = t.xy[i].y(), h = t.h[i];
    Eigen::Vector3d q;
    if (R > 0) {
      // The sphere's point whose tangent-plane projection is (x, y) (the frame's origin is R up).
      const double z = std::sqrt(std::max(0.0, R * R - x * x - y * y));
      q = (x * frame_.east + y * frame_.north + z * frame_.up).normalized() * (R + h);
    } else {
      q = frame_.origin + x * frame_.east + y * frame_.north + h * frame_.up;
    }
    p.positions.push_back(q);
    p.heights.push_back(h);
    const core::GridPoint n = edit::nearestVertex(*chart_, q);
    p.gridIndex.push_back(g.index(n.u, n.v));
  }
  p.indices.reserve(3 * t.triangles.size());
  for (const auto& tri : t.triangles) p.indices.insert(p.indices.end(), tri.begin(), tri.end());
  const bool sphere = R > 0;
  const int m = g.m();
  // It stands for the points two cells or more inside its domain: the view's triangles it
  // replaces then lie well inside it, and its border ring overlaps the view's kept triangles
  // (a triangle with a corner on the border to rounding left out could uncover a sliver).
  const double margin = marginCells * smallestSpacing(*chart_);
  for (const Point& q : points_) {
    if (sand_->tin().depthInside(q.xy) < margin) continue;
    if (sphere && (q.v == 0 || q.v == m)) {
      for (int u = 0; u <= m; ++u) p.replaces.push_back(g.index(u, q.v));
      continue;
    }
    p.replaces.push_back(g.index(q.u, q.v));
    if (sphere && q.u == 0) p.replaces.push_back(g.index(m, q.v));
  }
  std::sort(p.replaces.begin(), p.replaces.end());
  return p;
}

bool StrokeTin::holds(std::span<const float> heights) const {
  const core::GridSize g = chart_->grid();
  for (std::size_t k = 0; k < points_.size(); ++k)
    if (heights[g.index(points_[k].u, points_[k].v)] != left_[k]) return false;
  return true;
}

StrokeTinWrite StrokeTin::writeBack(std::span<float> heights, const SandGrid& cells,
                                    float heightLimit) {
  const core::GridSize g = chart_->grid();
  const int m = g.m();
  const bool sphere = chart_->sphereRadius() > 0;
  StrokeTinWrite w;
  // The TIN's change at every point, then the grid's own volume (sum A h) put back on the points
  // that changed, then floats with the rounding carried on.
  std::vector<double> next(points_.size()), after(points_.size());
  double change = 0, changedArea = 0;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const double h = left_[k];
    after[k] = sand_->tin().heightAt(points_[k].xy);
    // Outside the TIN's hull (a left-out point at the region's edge, or one on it to rounding).
    next[k] = std::isnan(after[k]) || std::isnan(surface_[k]) ? h : h + (after[k] - surface_[k]);
    if (next[k] != h) {
      change += cells.area(points_[k].v) * (next[k] - h);
      changedArea += cells.area(points_[k].v);
      ++w.changed;
    }
  }
  w.volumeCorrection = -change;
  const double limit = heightLimit;
  double carry = 0;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    surface_[k] = after[k];
    if (next[k] == double(left_[k])) continue;
    const double area = cells.area(points_[k].v);
    const double exact = next[k] - change / changedArea;
    const double want = exact + carry / area;
    const float f = float(std::clamp(want, -limit, limit));
    if (std::abs(want) < limit) carry += area * (exact - double(f));
    left_[k] = f;
    const int u = points_[k].u, v = points_[k].v;
    if (sphere && (v == 0 || v == m)) {
      std::fill_n(heights.begin() + std::ptrdiff_t(g.index(0, v)), g.side(), f);
    } else {
      heights[g.index(u, v)] = f;
      if (sphere && u == 0) heights[g.index(m, v)] = f;
    }
  }
  return w;
}

}  // namespace ps::sand
