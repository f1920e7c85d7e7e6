#pragma once
// The sand TIN as an edit tool: each application makes a TIN of the region around the control
// vertex from the terrain's heights (in a local frame: the tangent plane at the control vertex,
// so it works the same at a pole, across the seam and on a flat grid), stamps the tool into it,
// erodes it along its edges and removes its flat vertices (sand/tin_sand, paper 000), and writes
// the result back into the grid's heights, keeping the grid's volume. Through the edit pipeline
// it gets what every tool gets: undo, the journal, saves, exports and the 4-8 mesh's bounds.
//
// The TIN holds the grid's points of the region (thinned to one per equatorial cell where a
// lat-long chart crowds them near a pole) at their heights; every grid point then takes the
// change of the TIN's surface, so points the TIN left out keep their own detail. The tool's
// imprint is crisp in the TIN and reaches the grid at the grid's spacing.
#include <memory>
#include <string>

#include "core/chart.hpp"
#include "edit/region_growing.hpp"
#include "edit/tool.hpp"
#include "sand/sand_grid.hpp"
#include "sand/tin_sand.hpp"

namespace ps::sand {

struct TinSandToolSettings {
  double radius = 100e3;      // m: the stamp's radius (a regular polygon's corners on it)
  int segments = 24;          // the stamp's corners, 3..256
  double regionRadius = 3.0;  // the TIN's region around the control vertex, x radius, [2.5, 8]
  double spacing = 0.25;      // between stamps of a stroke, x radius, (0, 1]
  int erosionSteps = 8;       // erosion iterations after each stamp, 0..1000
  // Material, flat angle, removal. The removal is off: the TIN is made for one stamp and
  // dropped, so thinning it gains nothing, and on a planet a vertex within theta_flat of its
  // neighbours can still be tens of metres off the interpolated surface (tan 0.4 deg x a 20 km
  // cell = 140 m), which writing back would flatten.
  TinSandSettings sand = [] {
    TinSandSettings s;
    s.removeRedundant = false;
    return s;
  }();

  // Throws core::InputError naming the first bad field; with a chart, also checks the radius
  // against its grid (at least two cells) and the planet.
  void validate(const core::Chart* chart = nullptr) const;
  bool operator==(const TinSandToolSettings&) const = default;
};

// What the last apply() did.
struct TinSandToolStats {
  std::size_t gridVertices = 0;      // distinct grid points in the region
  std::size_t tinStartVertices = 0;  // the TIN's points (thinned where the chart crowds them)
  std::size_t tinVertices = 0;       // after the stamp, erosion and removal
  std::size_t tinTriangles = 0;
  std::size_t removed = 0;          // flat vertices removed
  double displacedVolume = 0;       // m^3 the stamp moved onto its rampart
  double gridVolumeCorrection = 0;  // m^3 put back after sampling the TIN onto the grid
  std::size_t changed = 0;          // grid points whose height changed
};

class TinSandTool final : public edit::Tool {
 public:
  TinSandTool(std::shared_ptr<const core::Chart> chart, TinSandToolSettings settings = {});

  const TinSandToolSettings& settings() const { return settings_; }
  void setSettings(const TinSandToolSettings& s) { settings_ = s; }
  const TinSandToolStats& lastStats() const { return stats_; }

  std::string name() const override { return "tin-sand"; }
  void validate() const override { settings_.validate(chart_.get()); }
  double radius() const override { return settings_.radius; }
  double spacing() const override { return settings_.spacing * settings_.radius; }
  const edit::Region& footprint(const edit::ToolContext& ctx) const override;
  terrain::GridRegion apply(const edit::ToolContext& ctx, std::span<float> heights) const override;

 private:
  std::shared_ptr<const core::Chart> chart_;
  SandGrid cells_;  // the grid's cell areas (and the refusal of charts the sand core lacks)
  TinSandToolSettings settings_;
  mutable edit::RegionGrower grower_;
  mutable edit::Region footprint_;
  mutable TinSandToolStats stats_;
};

}  // namespace ps::sand
