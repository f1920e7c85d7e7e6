#pragma once
#include <memory>
#include <span>
#include <string>

#include "core/chart.hpp"
#include "edit/region_growing.hpp"
#include "edit/tool.hpp"
#include "sand/listener.hpp"
#include "sand/material.hpp"
#include "sand/sand_grid.hpp"

namespace ps::sand {

struct DisplacementSettings {
  // The tool is a sphere of this radius (m) centred on the tool position. At least one grid cell
  // (the chart's largest spacing) and at most the planet's radius (a flat grid's extent).
  double radius = 100e3;
  // Width of the rampart ring around the crater, as a multiple of radius; (0, 4].
  double rampartWidth = 1.0;
  // Stroke stamp spacing as a fraction of radius; (0, 1].
  double spacing = 0.25;
  // The material the displaced heights settle as (handed to the listener).
  Material material = Material::sand();

  // Throws core::InputError naming the first bad field; with a chart, also checks the radius
  // against the grid and the planet.
  void validate(const core::Chart* chart = nullptr) const;
  bool operator==(const DisplacementSettings&) const = default;
};

// What the last apply() moved (volumes in m^3 as sum_i A_i dh_i, see SandGrid).
struct DisplacementStats {
  double removedVolume = 0;      // taken from under the sphere (double)
  double depositedVolume = 0;    // put on the rampart (double; equal to removedVolume to rounding)
  double floatVolumeChange = 0;  // of the float heights as stored (rounding to float included)
  double contactRadius = 0;      // largest distance from the control vertex of a lowered vertex
  std::size_t lowered = 0, raised = 0;  // distinct points
};

// Paper 004's displacement (section 3.1) with the sphere's exact shape instead of the sampled
// filter pair: a sphere of radius r centred on the tool position is pressed into the surface.
//   * negative filter: every vertex whose surface lies above the sphere's lower surface along
//     its up direction is lowered onto it; V = sum_i A_i (h_i - h_i') is the volume removed;
//   * positive filter: V is deposited on a rampart ring around the crater, from the contact
//     radius a (the farthest lowered vertex from the control vertex) to a + w (w = rampartWidth
//     r), with the profile p(t) = 1 - 3t^2 + 2t^3, t = (d - a) / w, scaled so that
//     sum_i A_i dh_i = V exactly in double.
// Heights are computed in double and rounded to float once (the float volume changes by the
// rounding only: |dV| <= sum_i A_i ulp(h_i) / 2). Dragging the tool stamps it along the stroke:
// each stamp pushes what lies in the sphere's way to the sides and ahead, leaving a furrow with
// ridges.
//
// footprint() is larger than V_d (= the vertices within r of the control vertex): it is grown
// to the rampart's outer edge plus two cells, and apply() writes only there.
class DisplacementTool final : public edit::Tool {
 public:
  // `chart` is the terrain's chart (for the radius checks and cell areas); `listener` (optional,
  // must outlive the tool) is told each region the tool changed.
  DisplacementTool(std::shared_ptr<const core::Chart> chart, DisplacementSettings settings = {},
                   EditListener* listener = nullptr);

  const DisplacementSettings& settings() const { return settings_; }
  void setSettings(const DisplacementSettings& s) { settings_ = s; }
  void setListener(EditListener* listener) { listener_ = listener; }
  const DisplacementStats& lastStats() const { return stats_; }

  std::string name() const override { return "displace"; }
  void validate() const override { settings_.validate(&grid_.chart()); }
  double radius() const override { return settings_.radius; }
  double spacing() const override { return settings_.spacing * settings_.radius; }
  const edit::Region& footprint(const edit::ToolContext& ctx) const override;
  bool footprintIsRegion() const override { return false; }
  terrain::VertexBox apply(const edit::ToolContext& ctx, std::span<float> heights) const override;

 private:
  // Distance (chord on the reference surface) from the control vertex within which the sphere
  // can reach, and the footprint radius.
  double reach(const edit::ToolContext& ctx) const;
  const edit::Region& grow(const edit::ToolContext& ctx) const;

  SandGrid grid_;
  DisplacementSettings settings_;
  EditListener* listener_ = nullptr;
  mutable edit::RegionGrower grower_;
  mutable edit::Region footprint_;
  mutable DisplacementStats stats_;
};

// The chart's largest distance between neighbouring vertices ("one cell"), or a bound of it:
// 2 pi R / m on the lat-long chart (the equator's) and on the octahedral one, max(dx, dy) on a
// flat chart, 2 pi (R + r) / m on a torus (its outer equator), max(2 pi R, L) / m on a cylinder.
double largestSpacing(const core::Chart& chart);
// Whether the sand core's cells (SandGrid) are defined on this chart: lat-long, flat,
// octahedral, torus, cylinder.
bool sandCoreKnows(const core::Chart& chart);

}  // namespace ps::sand
