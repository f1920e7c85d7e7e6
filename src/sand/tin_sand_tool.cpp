#include "sand/tin_sand_tool.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "sand/displacement.hpp"
#include "sand/sand_grid.hpp"

namespace ps::sand {

double smallestCurvatureRadius(const core::Chart& chart) {
  if (chart.sphereRadius() > 0) return chart.sphereRadius();
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart))
    return std::min(torus->minorRadius(), torus->majorRadius() - torus->minorRadius());
  if (const auto* tube = dynamic_cast<const core::CylinderChart*>(&chart))
    return tube->tubeRadius();
  return INFINITY;
}

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
  if (!(std::isfinite(tolerance) && tolerance >= 0 && tolerance <= 0.1))
    throw core::InputError("TIN sand tool: tolerance " + core::exactNumber(tolerance) +
                           " x the radius is outside [0, 0.1]");
  if (!(std::isfinite(detailRadius) && detailRadius >= 0 && detailRadius <= 8))
    throw core::InputError("TIN sand tool: detail radius " + core::exactNumber(detailRadius) +
                           " x the radius is outside [0, 8]");
  if (!(std::isfinite(spacing) && spacing > 0 && spacing <= 1))
    throw core::InputError("TIN sand tool: spacing " + core::exactNumber(spacing) +
                           " x the radius is outside (0, 1]");
  if (erosionSteps < 0 || erosionSteps > 1000)
    throw core::InputError("TIN sand tool: " + std::to_string(erosionSteps) +
                           " erosion steps is outside 0 .. 1000");
  sand.validate();
  if (!chart) return;
  // Its region is a height field over the tangent plane at the stroke's first stamp, its points
  // the grid's distinct points (SandGrid's cells, on every chart the sand core knows), so it
  // works across the octahedral chart's folds and the tubes' seams as across lat-long's seam.
  if (!sandCoreKnows(*chart))
    throw core::InputError(
        "TIN sand tool: it works on the lat-long, octahedral, torus, cylinder "
        "and flat charts, not on '" +
        chart->name() + "'");
  const double cell = largestSpacing(*chart);
  if (radius < 2 * cell)
    throw core::InputError("TIN sand tool: radius " + core::exactNumber(radius) +
                           " m is under two grid cells (" + core::exactNumber(2 * cell) + " m)");
  // The region shrinks to a quarter of the surface's smallest radius of curvature (a sphere's
  // radius, a torus's tube radius or the inner equator's R - r, a cylinder's radius), never
  // under 2.5 radii.
  const double curvature = smallestCurvatureRadius(*chart);
  if (std::isfinite(curvature) && 2.5 * radius > 0.25 * curvature)
    throw core::InputError("TIN sand tool: its region (at least " +
                           core::exactNumber(2.5 * radius) + " m) is over " +
                           (chart->sphereRadius() > 0 ? std::string("a quarter of the planet's radius")
                                                : "a quarter of the " + chart->name() +
                                                      "'s smallest radius of "
                                                      "curvature (" +
                                                      core::exactNumber(curvature) + " m)") +
                           ", too curved for one tangent plane");
}

TinSandTool::TinSandTool(std::shared_ptr<const core::Chart> chart, TinSandToolSettings settings)
    : chart_(std::move(chart)), cells_(chart_), settings_(std::move(settings)) {}

double TinSandTool::regionMetres(const core::Chart& chart) const {
  const double r = settings_.regionRadius * settings_.radius;
  return std::min(r, 0.25 * smallestCurvatureRadius(chart));
}

bool TinSandTool::reusable(const edit::ToolContext& ctx) const {
  if (!settings_.persistent || !strokeTin_ || !(strokeTinSettings_ == settings_)) return false;
  const core::Chart& chart = ctx.terrain.chart();
  const Eigen::Vector2d c =
      strokeTin_->frame().project(chart.position(ctx.control.u, ctx.control.v, 0.0));
  return strokeTin_->sand().tin().depthInside(c) >= kReuseDepth * settings_.radius &&
         strokeTin_->holds(ctx.terrain.heights());
}

const edit::Region& TinSandTool::footprint(const edit::ToolContext& ctx) const {
  if (reusable(ctx)) return strokeTin_->footprint();
  grower_.grow(ctx.field, regionMetres(ctx.terrain.chart()), footprint_);
  return footprint_;
}

terrain::VertexBox TinSandTool::apply(const edit::ToolContext& ctx,
                                      std::span<float> heights) const {
  settings_.validate(&ctx.terrain.chart());
  stats_ = {};
  ++stamps_;
  const core::Chart& chart = ctx.terrain.chart();
  if (!reusable(ctx)) {
    const edit::Region& F = footprint(ctx);
    strokeTin_.reset();  // its TIN's memory back before the next is made
    strokeTin_.emplace(chart, heights, F, ctx.control, settings_.tolerance * settings_.radius,
                       settings_.sand);
    strokeTinSettings_ = settings_;
    ++tinsMade_;
    stats_.madeTin = true;
  }
  StrokeTin& region = *strokeTin_;
  TinSand& sand = region.sand();
  stats_.generation = region.generation();
  stats_.gridVertices = region.gridPoints();
  stats_.tinStartVertices = stats_.madeTin ? region.startVertices() : sand.tin().vertexCount();

  // The stamp's centre in the region's plane; the tool's bottom: the lowest point of its sphere,
  // as the displacement tool presses, its height above the reference surface measured at the
  // control vertex.
  const TangentFrame here(chart, ctx.control);
  const Eigen::Vector2d centre = region.frame().project(here.origin);
  const double bottom = (ctx.input.position - here.origin).dot(here.up) - settings_.radius;
  if (settings_.detailRadius > 0)
    stats_.densified = region.densify(centre, settings_.detailRadius * settings_.radius);
  const TinStampTool tool = TinStampTool::disc(settings_.radius, settings_.segments);
  const TinStampStats stamped = sand.stamp(centre, bottom, tool);
  stats_.displacedVolume = stamped.displacedVolume;
  for (int s = 0; s < settings_.erosionSteps; ++s) sand.erode();
  stats_.removed = sand.removeRedundant();
  stats_.tinVertices = sand.tin().vertexCount();
  stats_.tinTriangles = sand.tin().triangleCount();

  const StrokeTinWrite w = region.writeBack(heights, cells_, ctx.heightLimit);
  stats_.changed = w.changed;
  stats_.gridVolumeCorrection = w.volumeCorrection;
  const terrain::VertexBox dirty = region.footprint().bounds();
  if (!settings_.persistent) strokeTin_.reset();
  return dirty;
}

}  // namespace ps::sand
