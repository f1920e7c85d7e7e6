#pragma once
// The sand TIN as an edit tool: a TIN of the region around a stroke's first stamp, made from
// the terrain's heights with the TIN export's error-bounded generation (sand/stroke_tin: in the
// tangent plane at that stamp, so it works the same at a pole, across lat-long's seam, across
// the octahedral chart's folds and the torus's and the cylinder's seams, and on a flat grid),
// persists while the stroke's stamps stay inside it; each stamp presses the tool into
// it, erodes it along its edges and removes its flat vertices (sand/tin_sand, paper 000), and
// the result is written back into the grid's heights, keeping the grid's volume. Through the
// edit pipeline it gets what every tool gets: undo, the journal, saves, exports and the 4-8
// mesh's bounds.
//
// A new TIN is made at the start of every stroke (Tool::beginStroke), when a stamp's reach
// leaves the region, and when the grid no longer holds what the region last wrote (an undo or
// another tool between stamps): a stroke's result depends only on the heights at its start.
#include <memory>
#include <optional>
#include <string>

#include "core/chart.hpp"
#include "edit/region_growing.hpp"
#include "edit/tool.hpp"
#include "sand/sand_grid.hpp"
#include "sand/stroke_tin.hpp"
#include "sand/tin_sand.hpp"

namespace ps::sand {

// The smallest radius of curvature of `chart`'s reference surface (m): a sphere's radius, a
// torus's min(r, R - r) (its tube; the inner equator's R - r round the axis), a cylinder's
// radius; infinite on a flat chart. The region TIN's tangent plane holds a quarter of it.
double smallestCurvatureRadius(const core::Chart& chart);

struct TinSandToolSettings {
  double radius = 100e3;  // m: the stamp's radius (a regular polygon's corners on it)
  int segments = 24;      // the stamp's corners, 3..256
  // The TIN's region around a stroke's first stamp, x radius, [2.5, 8] (on a sphere at most a
  // quarter of its radius, on a tube of its smallest radius of curvature: the tangent plane's
  // distortion stays under 3 %). Stamps reuse it while their reach (2.05 radii: the rim and the
  // rampart) lies kReuseDepth radii inside it.
  double regionRadius = 5.0;
  // The region TIN's largest vertical error at the grid's points, x radius, >= 0 (0: every
  // grid point a vertex, error 0).
  double tolerance = 1e-3;
  // Around each stamp, within this x radius, the region TIN takes every grid point at the
  // grid's height before the stamp (StrokeTin::densify; 0: none), [0, 8]. 2.05: the stamp's
  // reach, so a stamp and its erosion act on the grid's every point as on the all-points TIN
  // (one stamp without erosion: 0.06 m RMS from it; 1.25: 6.6 m; 0: 8.5 m, and with erosion
  // on a coarse TIN 53 m: its long edges flow otherwise).
  double detailRadius = 2.05;
  // Off: a TIN made afresh for every stamp (the tool as it was first written).
  bool persistent = true;
  double spacing = 0.25;  // between stamps of a stroke, x radius, (0, 1]
  int erosionSteps = 8;   // erosion iterations after each stamp, 0..1000
  // Material, flat angle, removal. The removal is off: on a planet a vertex within theta_flat
  // of its neighbours can still be tens of metres off the interpolated surface (tan 0.4 deg x a
  // 20 km cell = 140 m), which writing back would flatten; the region's TIN holds only what its
  // tolerance needs from the start.
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
  std::size_t removed = 0;             // flat vertices removed
  double displacedVolume = 0;          // m^3 the stamp moved onto its rampart
  double gridVolumeCorrection = 0;     // m^3 put back after sampling the TIN onto the grid
  std::size_t changed = 0;             // grid points whose height changed
  std::size_t densified = 0;           // grid points inserted around the stamp
  bool madeTin = false;                // this stamp made the region's TIN (else reused it)
  tin::ScatteredTinReport generation;  // of the region's TIN (the last one made)
};

class TinSandTool final : public edit::Tool {
 public:
  static constexpr double kReuseDepth = 2.25;  // x radius: the reach 2.05, and a margin

  TinSandTool(std::shared_ptr<const core::Chart> chart, TinSandToolSettings settings = {});

  const TinSandToolSettings& settings() const { return settings_; }
  void setSettings(const TinSandToolSettings& s) { settings_ = s; }
  const TinSandToolStats& lastStats() const { return stats_; }
  // Region TINs made since construction (a stroke that reuses one makes one).
  std::size_t tinsMade() const { return tinsMade_; }
  // Stamps applied since construction: the region's TIN changes at each (a view that draws it
  // keys on this and the planet's revision).
  std::size_t stamps() const { return stamps_; }
  // The region's TIN as the last stamp left it (null before the first stamp, and after a
  // stroke's start until its first stamp).
  const StrokeTin* strokeTin() const { return strokeTin_ ? &*strokeTin_ : nullptr; }
  // The region's radius (m) on `chart`: regionRadius x radius, at most a quarter of the
  // surface's smallest radius of curvature (smallestCurvatureRadius).
  double regionMetres(const core::Chart& chart) const;

  std::string name() const override { return "tin-sand"; }
  void validate() const override { settings_.validate(chart_.get()); }
  double radius() const override { return settings_.radius; }
  double spacing() const override { return settings_.spacing * settings_.radius; }
  const edit::Region& footprint(const edit::ToolContext& ctx) const override;
  bool footprintIsRegion() const override { return false; }
  terrain::VertexBox apply(const edit::ToolContext& ctx, std::span<float> heights) const override;
  void beginStroke() const override { strokeTin_.reset(); }

 private:
  // Whether the stamp at ctx can use the region TIN as it is.
  bool reusable(const edit::ToolContext& ctx) const;

  std::shared_ptr<const core::Chart> chart_;
  SandGrid cells_;  // the grid's cell areas (and the refusal of charts the sand core lacks)
  TinSandToolSettings settings_;
  mutable edit::RegionGrower grower_;
  mutable edit::Region footprint_;
  mutable TinSandToolStats stats_;
  mutable std::optional<StrokeTin> strokeTin_;
  mutable TinSandToolSettings strokeTinSettings_;  // the settings strokeTin_ was made with
  mutable std::size_t tinsMade_ = 0;
  mutable std::size_t stamps_ = 0;
};

}  // namespace ps::sand
