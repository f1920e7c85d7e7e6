#include "sand/displacement.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"

namespace ps::sand {

bool sandCoreKnows(const core::Chart& chart) {
  return dynamic_cast<const core::LatLongChart*>(&chart) ||
         dynamic_cast<const core::FlatChart*>(&chart) ||
         dynamic_cast<const core::OctahedralChart*>(&chart) ||
         dynamic_cast<const core::TorusChart*>(&chart) ||
         dynamic_cast<const core::CylinderChart*>(&chart);
}

double largestSpacing(const core::Chart& chart) {
  // A sphere's other charts space their vertices closer than lat-long's equator does (`bench
  // charts` at 8193^2: octahedral at most 0.84x, its central projection 0.78x): the same bound.
  if (dynamic_cast<const core::LatLongChart*>(&chart) ||
      dynamic_cast<const core::OctahedralChart*>(&chart)) {
    return 2.0 * std::numbers::pi * chart.sphereRadius() / chart.grid().m();
  }
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(&chart)) {
    return std::max(flat->dx(), flat->dy());
  }
  const double m = chart.grid().m();
  // The torus's outer equator (its longest steps in u) and a step round the tube.
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart)) {
    return 2.0 * std::numbers::pi * (torus->majorRadius() + torus->minorRadius()) / m;
  }
  if (const auto* cyl = dynamic_cast<const core::CylinderChart*>(&chart)) {
    return std::max(2.0 * std::numbers::pi * cyl->tubeRadius(), cyl->length()) / m;
  }
  throw core::InputError(
      "the sand core works on the lat-long, flat, octahedral, torus and "
      "cylinder charts, not on '" +
      chart.name() + "'");
}

namespace {
// The tube's radius of a torus (its minor radius) or a cylinder; 0 on other charts.
double tubeRadius(const core::Chart& chart) {
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart))
    return torus->minorRadius();
  if (const auto* cyl = dynamic_cast<const core::CylinderChart*>(&chart)) return cyl->tubeRadius();
  return 0.0;
}
}  // namespace

void DisplacementSettings::validate(const core::Chart* chart) const {
  if (!std::isfinite(radius) || !(radius > 0.0)) {
    throw core::InputError("tool radius r = " + core::exactNumber(radius) +
                           " m must be finite and > 0");
  }
  if (chart) {
    const double cell = largestSpacing(*chart);
    if (radius < cell) {
      throw core::InputError("tool radius r = " + core::exactNumber(radius) +
                             " m is below one grid cell (" + core::exactNumber(cell) + " m)");
    }
    if (chart->sphereRadius() > 0.0) {
      if (radius > chart->sphereRadius()) {
        throw core::InputError("tool radius r = " + core::exactNumber(radius) +
                               " m is larger than the planet (radius " +
                               core::exactNumber(chart->sphereRadius()) + " m)");
      }
    } else if (const double tube = tubeRadius(*chart); tube > 0.0) {
      // A sphere wider than the tube would press through it (and, on a torus, across the hole).
      if (radius > tube) {
        throw core::InputError("tool radius r = " + core::exactNumber(radius) +
                               " m is larger than the " + chart->name() + "'s tube (radius " +
                               core::exactNumber(tube) + " m)");
      }
    } else if (const auto* flat = dynamic_cast<const core::FlatChart*>(chart)) {
      const double extent = chart->grid().m() * std::max(flat->dx(), flat->dy());
      if (radius > extent) {
        throw core::InputError("tool radius r = " + core::exactNumber(radius) +
                               " m is larger than the grid (extent " + core::exactNumber(extent) +
                               " m)");
      }
    }
  }
  if (!std::isfinite(rampartWidth) || !(rampartWidth > 0.0) || rampartWidth > 4.0) {
    throw core::InputError("rampart width = " + core::exactNumber(rampartWidth) +
                           " (a multiple of the tool radius) must be in (0, 4]");
  }
  if (!std::isfinite(spacing) || !(spacing > 0.0) || spacing > 1.0) {
    throw core::InputError("spacing = " + core::exactNumber(spacing) +
                           " (a fraction of the tool radius) must be in (0, 1]");
  }
  material.validate();
}

DisplacementTool::DisplacementTool(std::shared_ptr<const core::Chart> chart,
                                   DisplacementSettings settings, EditListener* listener)
    : grid_(std::move(chart)), settings_(std::move(settings)), listener_(listener) {}

double DisplacementTool::reach(const edit::ToolContext& ctx) const {
  const double r = settings_.radius;
  const double R = grid_.chart().sphereRadius();
  if (!(R > 0.0)) return r;
  const double L = ctx.input.position.norm();
  if (!(L > r)) return 2.0 * R;  // the sphere holds the planet's centre: it can reach anywhere
  const double theta = std::asin(std::min(1.0, r / L));
  return 2.0 * R * std::sin(0.5 * theta);
}

const edit::Region& DisplacementTool::grow(const edit::ToolContext& ctx) const {
  double radius =
      reach(ctx) + settings_.rampartWidth * settings_.radius + 2.0 * largestSpacing(grid_.chart());
  const double R = grid_.chart().sphereRadius();
  if (R > 0.0) radius = std::min(radius, 2.05 * R);
  grower_.grow(ctx.field, radius, footprint_);
  return footprint_;
}

const edit::Region& DisplacementTool::footprint(const edit::ToolContext& ctx) const {
  return grow(ctx);
}

terrain::VertexBox DisplacementTool::apply(const edit::ToolContext& ctx,
                                           std::span<float> heights) const {
  settings_.validate(&ctx.terrain.chart());
  if (ctx.terrain.grid().n() != grid_.grid().n() ||
      ctx.terrain.chart().name() != grid_.chart().name() ||
      ctx.terrain.chart().sphereRadius() != grid_.chart().sphereRadius()) {
    throw core::InputError("displacement tool: made for a " + grid_.chart().name() + " " +
                           grid_.grid().label() + " chart, applied to a " +
                           ctx.terrain.chart().name() + " " + ctx.terrain.grid().label() + " one");
  }
  stats_ = {};
  const edit::Region& F = grow(ctx);
  const core::Chart& chart = ctx.terrain.chart();
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const bool sphere = grid_.sphere();
  // The octahedral chart, the torus, the cylinder: a point once, at its canonical vertex.
  const bool glued = grid_.glued();
  const Eigen::Vector3d c = ctx.input.position;
  const double r = settings_.radius;
  const double r2 = r * r;

  // Negative filter: per distinct point, the depth removed and the distance from the control
  // vertex.
  struct Entry {
    int u, v;
    double dh, d;
  };
  std::vector<Entry> entries;
  entries.reserve(F.pointCount());
  CompensatedSum removed;
  double a = 0.0;
  F.forEachSpan([&](int v, int ub, int ue) {
    for (int u = ub; u <= ue; ++u) {
      if (sphere && (u == m || ((v == 0 || v == m) && u != 0))) continue;  // one entry a point
      if (glued && !grid_.isCell(u, v)) continue;  // the region holds every twin of its points
      const double h = double(heights[g.index(u, v)]);
      const Eigen::Vector3d base = chart.position(u, v, 0.0);
      const Eigen::Vector3d n = chart.up(u, v);
      const Eigen::Vector3d q = base - c;
      const double p = n.dot(q);
      double qq = q.x() * q.x() + q.y() * q.y();
      qq += q.z() * q.z();
      const double disc = p * p - qq + r2;
      double dh = 0.0;
      if (disc >= 0.0) {
        const double low = -p - std::sqrt(disc);  // the sphere's lower surface on this line
        if (h > low) dh = h - low;
      }
      const double d = std::sqrt(ctx.field.distance2(u, v));
      entries.push_back({u, v, dh, d});
      if (dh > 0.0) {
        removed.add(grid_.cellArea(u, v) * dh);
        a = std::max(a, d);
        ++stats_.lowered;
      }
    }
  });
  const double V = removed.value();
  if (!(V > 0.0)) return terrain::VertexBox::none();

  // Positive filter: the rampart ring (a, a + w).
  const double w = settings_.rampartWidth * r;
  auto profile = [&](const Entry& e) {
    if (e.dh > 0.0 || !(e.d > a) || !(e.d < a + w)) return 0.0;
    const double t = (e.d - a) / w;
    return 1.0 - t * t * (3.0 - 2.0 * t);
  };
  CompensatedSum weights;
  for (const Entry& e : entries) weights.add(grid_.cellArea(e.u, e.v) * profile(e));
  const double S = weights.value();
  if (!(S > 0.0)) return terrain::VertexBox::none();  // nowhere to put it (the whole planet)
  const double k = V / S;

  const double limit = ctx.heightLimit;
  CompensatedSum deposited, floatChange;
  // Rounding to float with the residual carried to the next vertex (error diffusion): the
  // floats' volume then differs from the exact one by one vertex's rounding, not a random walk
  // over every vertex the stamp touched.
  double carry = 0.0;
  int vFirst = m + 1, vLast = -1, uFirst = m + 1, uLast = -1;
  for (const Entry& e : entries) {
    const double p = profile(e);
    if (!(e.dh > 0.0) && !(p > 0.0)) continue;
    const double add = e.dh > 0.0 ? -e.dh : k * p;
    if (add > 0.0) {
      deposited.add(grid_.cellArea(e.u, e.v) * add);
      ++stats_.raised;
    }
    const float old = heights[g.index(e.u, e.v)];
    const double area = grid_.cellArea(e.u, e.v), exact = double(old) + add;
    const double want = exact + carry / area;
    const float f = static_cast<float>(std::clamp(want, -limit, limit));
    if (std::abs(want) < limit) carry += area * (exact - double(f));
    floatChange.add(area * (double(f) - double(old)));
    if (sphere && (e.v == 0 || e.v == m)) {
      std::fill_n(heights.begin() + std::ptrdiff_t(g.index(0, e.v)), g.side(), f);
    } else if (glued) {
      core::GridPoint tw[4];
      const int nt = chart.twins(e.u, e.v, tw);
      for (int j = 0; j < nt; ++j) {
        heights[g.index(tw[j].u, tw[j].v)] = f;
        vFirst = std::min(vFirst, tw[j].v);
        vLast = std::max(vLast, tw[j].v);
        uFirst = std::min(uFirst, tw[j].u);
        uLast = std::max(uLast, tw[j].u);
      }
    } else {
      heights[g.index(e.u, e.v)] = f;
      if (sphere && e.u == 0) heights[g.index(m, e.v)] = f;
    }
    vFirst = std::min(vFirst, e.v);
    vLast = std::max(vLast, e.v);
  }
  stats_.removedVolume = V;
  stats_.depositedVolume = deposited.value();
  stats_.floatVolumeChange = floatChange.value();
  stats_.contactRadius = a;
  terrain::VertexBox dirty = F.bounds();
  dirty.vBegin = vFirst;
  dirty.vEnd = vLast;
  if (grid_.tube()) {
    // The region's box, as the brush reports it: its u range wraps the seam (the twins at u = m
    // of the points at u = 0 lie in it, as on lat-long), and on the torus the box is the
    // centre's half in v, whose image across the v seam (Terrain::commitEdit) holds the rest.
    if (chart.gluesSidesBeyondSeam()) dirty = F.bounds();
  } else if (glued) {  // the box of every vertex written, twins across the folds included
    dirty.uBegin = uFirst;
    dirty.uEnd = uLast;
  }
  if (listener_ && grid_.tube()) {
    // The settler marks what it is told: on the torus the written vertices beyond the centre's
    // half lie in the box's images (across the v seam and the midline), which it is told too.
    for (const terrain::VertexBox& image : terrain::gluedImages(chart, dirty))
      listener_->edited(image, settings_.material);
  } else if (listener_) {
    listener_->edited(dirty, settings_.material);
  }
  return dirty;
}

}  // namespace ps::sand
