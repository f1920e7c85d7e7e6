#include "sand/stroke_tin.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_set>

#include "core/flat_chart.hpp"
#include "edit/control_vertex.hpp"
#include "edit/grid_consistency.hpp"
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

// The TIN's lattice spacing and its thinning cell: the smallest spacing between grid points at
// the equator (lat-long: a meridian step), on a flat grid its smaller step, and on the glued
// charts (octahedral, torus, cylinder; no pole crowds their rows) the shorter of the two grid
// steps at the region's centre, the grid continued across a fold or a seam.
double latticeSpacing(const core::Chart& chart, core::GridPoint centre) {
  if (chart.hasPoleRows()) return std::numbers::pi * chart.sphereRadius() / chart.grid().m();
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(&chart))
    return std::min(flat->dx(), flat->dy());
  const Eigen::Vector3d c = chart.position(centre.u, centre.v, 0.0);
  double step = INFINITY;
  for (const auto& [du, dv] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
    const core::GridPoint n = chart.continued(centre.u + du, centre.v + dv);
    const double d = (chart.position(n.u, n.v, 0.0) - c).norm();
    if (d > 0) step = std::min(step, d);
  }
  return std::isfinite(step) ? step : largestSpacing(chart);
}

// The point of a tube's reference surface whose projection into `frame`'s plane is xy (a tube's
// region is a height field over its tangent plane, as a sphere's is): from the plane's point,
// each step moves to the surface's point under it (the chart's inverse) and corrects the plane
// point by what the projection missed. The region is at most a quarter of the surface's smallest
// radius of curvature, so the map is close to the identity and a few steps reach 1e-9 of it.
Eigen::Vector3d tubePointAt(const core::Chart& chart, const TangentFrame& frame,
                            const Eigen::Vector2d& xy, Eigen::Vector3d& up) {
  Eigen::Vector2d aim = xy;
  Eigen::Vector3d s = frame.origin, n = frame.up;
  for (int k = 0; k < 8; ++k) {
    const auto uv = chart.inverse(frame.origin + aim.x() * frame.east + aim.y() * frame.north);
    if (!uv) break;
    s = chart.positionAt(uv->x(), uv->y(), 0.0);
    n = (chart.positionAt(uv->x(), uv->y(), 1.0) - s).normalized();
    const Eigen::Vector2d miss = xy - frame.project(s);
    aim += miss;
    if (miss.norm() <= 1e-9 * (1.0 + xy.norm())) break;
  }
  up = n;
  return s;
}

}  // namespace

StrokeTin::StrokeTin(const core::Chart& chart, std::span<const float> heights,
                     const edit::Region& F, core::GridPoint centre, double tolerance,
                     const TinSandSettings& sand)
    : chart_(&chart),
      footprint_(F),
      frame_(chart, centre),
      spacing_(latticeSpacing(chart, centre)) {
  const core::GridSize g = chart.grid();
  // Every distinct point of the region once, at its canonical vertex (a pole row's u = 0, the
  // seam's u = 0, a folded side's or a torus seam's canonical twin): the grower takes every twin
  // of a point it reaches, and their positions are one point bit for bit, so the points on
  // either side of a fold or a seam lie side by side in the tangent plane.
  F.forEachSpan([&](int v, int ub, int ue) {
    for (int u = ub; u <= ue; ++u) {
      const core::GridPoint c = chart.canonical(u, v);
      if (c.u != u || c.v != v) continue;
      points_.push_back({u, v, frame_.project(chart.position(u, v, 0.0))});
      left_.push_back(heights[g.index(u, v)]);
    }
  });
  // The TIN's points: on a chart with pole rows at most one per cell of its smallest spacing at
  // the equator, so that the pole's crowded rows (thousands of points a few metres apart on a
  // lat-long chart) do not crowd the TIN too; everywhere else, and on every other chart, that
  // is every point.
  const double cell = chart.hasPoleRows() ? 0.99 * spacing_ : 0.0;
  std::unordered_set<std::uint64_t> taken;
  std::vector<Eigen::Vector3d> xyz;
  candidate_.assign(points_.size(), 0);
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const Eigen::Vector2d& p = points_[k].xy;
    if (cell == 0.0) {
      xyz.emplace_back(p.x(), p.y(), double(left_[k]));
      candidate_[k] = 1;
      continue;
    }
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
    sand_.emplace(tin::errorBoundedTin(xyz, spacing_, tolerance, &generation_), sand);
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
  // A tube's surface is no sphere and no plane: its patch is drawn, and the haptic path feels
  // the grid under it (what the TIN wrote back), as a patch without a plane is.
  const bool tube = R <= 0 && !dynamic_cast<const core::FlatChart*>(chart_);
  p.positions.reserve(t.xy.size());
  if (!tube) {
    p.plane.emplace();
    p.plane->origin = frame_.origin;
    p.plane->east = frame_.east;
    p.plane->north = frame_.north;
    p.plane->up = frame_.up;
    p.plane->radius = R > 0 ? R : 0.0;
    p.xy.assign(t.xy.begin(), t.xy.end());
  }
  for (std::size_t i = 0; i < t.xy.size(); ++i) {
    const double x = t.xy[i].x(), y = t.xy[i].y(), h = t.h[i];
    Eigen::Vector3d q;
    if (R > 0) {
      // The sphere's point whose tangent-plane projection is (x, y) (the frame's origin is R up).
      const double z = std::sqrt(std::max(0.0, R * R - x * x - y * y));
      q = (x * frame_.east + y * frame_.north + z * frame_.up).normalized() * (R + h);
    } else if (tube) {
      Eigen::Vector3d up;
      q = tubePointAt(*chart_, frame_, t.xy[i], up);
      q += h * up;
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
  const int m = g.m();
  // It stands for the points two cells or more inside its domain: the view's triangles it
  // replaces then lie well inside it, and its border ring overlaps the view's kept triangles
  // (a triangle with a corner on the border to rounding left out could uncover a sliver).
  const double margin = marginCells * spacing_;
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(points_.size());
  for (const Point& q : points_) xy.push_back(q.xy);
  const std::vector<std::uint8_t> deep = sand_->tin().deeperThan(xy, margin);
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (!deep[i]) continue;
    const Point& q = points_[i];
    if (chart_->hasPoleRows() && (q.v == 0 || q.v == m)) {
      for (int u = 0; u <= m; ++u) p.replaces.push_back(g.index(u, q.v));
      continue;
    }
    core::GridPoint twin[4];
    const int n = chart_->twins(q.u, q.v, twin);
    for (int k = 0; k < n; ++k) p.replaces.push_back(g.index(twin[k].u, twin[k].v));
  }
  std::sort(p.replaces.begin(), p.replaces.end());
  p.replaces.erase(std::unique(p.replaces.begin(), p.replaces.end()), p.replaces.end());
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
      const double area = cells.cellArea(points_[k].u, points_[k].v);
      change += area * (next[k] - h);
      changedArea += area;
      ++w.changed;
    }
  }
  w.volumeCorrection = -change;
  const double limit = heightLimit;
  double carry = 0;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    surface_[k] = after[k];
    if (next[k] == double(left_[k])) continue;
    const double area = cells.cellArea(points_[k].u, points_[k].v);
    const double exact = next[k] - change / changedArea;
    const double want = exact + carry / area;
    const float f = float(std::clamp(want, -limit, limit));
    if (std::abs(want) < limit) carry += area * (exact - double(f));
    left_[k] = f;
    // At every grid entry of the point: a pole row, a seam's twin, a folded side's mirror.
    edit::applyToVertex(*chart_, heights, points_[k].u, points_[k].v, f);
  }
  return w;
}

}  // namespace ps::sand
