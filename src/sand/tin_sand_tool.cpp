#include "sand/tin_sand_tool.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <unordered_set>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/octahedral_chart.hpp"
#include "sand/displacement.hpp"
#include "sand/sand_grid.hpp"

namespace ps::sand {

void TinSandToolSettings::validate(const core::Chart* chart) const {
  if (!(std::isfinite(radius) && radius > 0))
    throw core::InputError("TIN sand tool: radius " + core::exactNumber(radius) +
                           " m must be finite and > 0");
  if (segments < 3 || segments > 256)
    throw core::InputError("TIN sand tool: " + std::to_string(segments) +
                           " segments is outside 3 .. 256");
  if (!(std::isfinite(regionRadius) && regionRadius >= 2.5 && regionRadius <= 8))
    throw core::InputError("TIN sand tool: region radius " + core::exactNumber(regionRadius) +
                           " x the tool's is outside [2.5, 8] (the stamp and its rampart reach "
                           "2.05 x)");
  if (!(std::isfinite(spacing) && spacing > 0 && spacing <= 1))
    throw core::InputError("TIN sand tool: spacing " + core::exactNumber(spacing) +
                           " x the radius is outside (0, 1]");
  if (erosionSteps < 0 || erosionSteps > 1000)
    throw core::InputError("TIN sand tool: " + std::to_string(erosionSteps) +
                           " erosion steps is outside 0 .. 1000");
  sand.validate();
  if (!chart) return;
  // Its points and areas are per row (a pole row once, a seam twin once); the octahedral chart's
  // folds are not handled yet, while the grid sand core's tools work there.
  if (dynamic_cast<const core::OctahedralChart*>(chart))
    throw core::InputError("TIN sand tool: it works on the lat-long and flat charts, not on '" +
                           chart->name() + "'");
  const double cell = largestSpacing(*chart);
  if (radius < 2 * cell)
    throw core::InputError("TIN sand tool: radius " + core::exactNumber(radius) +
                           " m is under two grid cells (" + core::exactNumber(2 * cell) + " m)");
  if (chart->radius() > 0 && regionRadius * radius > 0.25 * chart->radius())
    throw core::InputError("TIN sand tool: its region (" +
                           core::exactNumber(regionRadius * radius) +
                           " m) is over a quarter of the planet's radius, too curved for one "
                           "tangent plane");
}

namespace {

// The smallest spacing between grid points at the equator (lat-long: a meridian step) or on a
// flat grid.
double smallestSpacing(const core::Chart& chart) {
  if (chart.radius() > 0) return std::numbers::pi * chart.radius() / chart.grid().m();
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(&chart))
    return std::min(flat->dx(), flat->dy());
  return largestSpacing(chart);
}

}  // namespace

TinSandTool::TinSandTool(std::shared_ptr<const core::Chart> chart, TinSandToolSettings settings)
    : chart_(std::move(chart)), cells_(chart_), settings_(std::move(settings)) {}

const edit::Region& TinSandTool::footprint(const edit::ToolContext& ctx) const {
  grower_.grow(ctx.field, settings_.regionRadius * settings_.radius, footprint_);
  return footprint_;
}

terrain::GridRegion TinSandTool::apply(const edit::ToolContext& ctx,
                                       std::span<float> heights) const {
  settings_.validate(&ctx.terrain.chart());
  stats_ = {};
  const edit::Region& F = footprint(ctx);
  const core::Chart& chart = ctx.terrain.chart();
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const bool sphere = chart.radius() > 0;

  // The local frame: the tangent plane at the control vertex on the reference surface.
  const Eigen::Vector3d origin = chart.position(ctx.control.u, ctx.control.v, 0.0);
  const Eigen::Vector3d up = chart.up(ctx.control.u, ctx.control.v);
  const Eigen::Vector3d across =
      std::abs(up.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d east = across.cross(up).normalized(), north = up.cross(east);

  // Every distinct point of the region (a pole row once, the seam's u = m as its twin u = 0).
  struct Point {
    int u, v;
    Eigen::Vector2d xy;
    double h;
  };
  std::vector<Point> points;
  F.forEachSpan([&](int v, int ub, int ue) {
    for (int u = ub; u <= ue; ++u) {
      if (sphere && (u == m || ((v == 0 || v == m) && u != 0))) continue;
      const Eigen::Vector3d p = chart.position(u, v, 0.0) - origin;
      points.push_back({u, v, {p.dot(east), p.dot(north)}, double(heights[g.index(u, v)])});
    }
  });
  // The TIN's points: at most one per cell of the chart's smallest spacing at the equator, so
  // that the pole's crowded rows (thousands of points a few metres apart on a lat-long chart)
  // do not crowd the TIN too; everywhere else that is every point.
  const double cell = 0.99 * smallestSpacing(chart);
  std::unordered_set<std::uint64_t> taken;
  std::vector<Eigen::Vector3d> xyz;
  for (const Point& p : points) {
    const auto ix = std::int64_t(std::floor(p.xy.x() / cell)) + (1 << 30);
    const auto iy = std::int64_t(std::floor(p.xy.y() / cell)) + (1 << 30);
    if (taken.insert((std::uint64_t(ix) << 32) | std::uint64_t(iy)).second)
      xyz.emplace_back(p.xy.x(), p.xy.y(), p.h);
  }
  TinSand sand(tin::DynamicTin(xyz), settings_.sand);
  stats_.gridVertices = points.size();
  stats_.tinStartVertices = sand.tin().vertexCount();
  // The TIN's surface before the stamp at every point (its own height where it is a vertex):
  // each point then takes the change of the surface, so a point the TIN left out keeps its
  // detail.
  std::vector<double> before(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) before[k] = sand.tin().heightAt(points[k].xy);

  // The tool's bottom: the lowest point of its sphere, as the displacement tool presses.
  const double bottom = (ctx.input.position - origin).dot(up) - settings_.radius;
  const TinStampTool tool = TinStampTool::disc(settings_.radius, settings_.segments);
  const TinStampStats stamped = sand.stamp({0.0, 0.0}, bottom, tool);
  stats_.displacedVolume = stamped.displacedVolume;
  for (int s = 0; s < settings_.erosionSteps; ++s) sand.erode();
  stats_.removed = sand.removeRedundant();
  stats_.tinVertices = sand.tin().vertexCount();
  stats_.tinTriangles = sand.tin().triangleCount();

  // Back onto the grid: the TIN's surface at every point, then the grid's own volume (sum A h)
  // put back on the points that changed, then floats with the rounding carried on.
  std::vector<double> next(points.size());
  double change = 0, changedArea = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const double after = sand.tin().heightAt(points[k].xy);
    // Outside the TIN's hull (a left-out point at the region's edge, or one on it to rounding).
    next[k] = std::isnan(after) || std::isnan(before[k]) ? points[k].h
                                                         : points[k].h + (after - before[k]);
    if (next[k] != points[k].h) {
      change += cells_.area(points[k].v) * (next[k] - points[k].h);
      changedArea += cells_.area(points[k].v);
      ++stats_.changed;
    }
  }
  stats_.gridVolumeCorrection = -change;
  const double limit = ctx.heightLimit;
  double carry = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (next[k] == points[k].h) continue;
    const double area = cells_.area(points[k].v);
    const double exact = next[k] - change / changedArea;
    const double want = exact + carry / area;
    const float f = float(std::clamp(want, -limit, limit));
    if (std::abs(want) < limit) carry += area * (exact - double(f));
    const int u = points[k].u, v = points[k].v;
    if (sphere && (v == 0 || v == m)) {
      std::fill_n(heights.begin() + std::ptrdiff_t(g.index(0, v)), g.side(), f);
    } else {
      heights[g.index(u, v)] = f;
      if (sphere && u == 0) heights[g.index(m, v)] = f;
    }
  }
  return F.bounds();
}

}  // namespace ps::sand
