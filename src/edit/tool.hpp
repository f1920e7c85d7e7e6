#pragma once
#include <Eigen/Core>
#include <span>
#include <string>

#include "core/grid.hpp"
#include "edit/distance_field.hpp"
#include "edit/region_growing.hpp"
#include "terrain/terrain.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::edit {

// What drives a tool for one application ("stamp").
struct ToolInput {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // tool tip in the planet frame (m)
  double dt = 0.0;  // seconds this application stands for (rate tools); finite and >= 0
};

// Everything the pipeline has prepared for one application of a tool.
struct ToolContext {
  const terrain::Terrain& terrain;  // chart, grid and current heights (read side)
  const DistanceField& field;       // centred on the control vertex
  const Region& region;     // V_d: vertices within radius() of the control vertex, on the sphere
  core::GridPoint control;  // canonical (seam and poles as u = 0)
  ToolInput input;
  float heightLimit;  // largest float <= terrain.heightLimit(): results must stay within
                      // +-heightLimit
  // The distances region growing computed for `region` (null: none kept; compute them with
  // `field`): a tool reads a row's from here instead of computing them again.
  const RowDistanceBlocks* distances = nullptr;
};

// An edit is a tool acting on a region and producing a dirty region. The pipeline finds the
// control vertex and V_d, calls apply(), keeps seam twins and pole rows consistent over the dirty
// region, updates the error bounds above it and records undo. Sand, erosion and haptic tools
// implement this same interface.
//
// Contract for apply():
//   * write only inside footprint() (the undo journal snapshots exactly that);
//   * make the new height a function of the point, not of the grid entry: seam twins
//     (u = 0 / u = m) and all entries of a pole row must receive identical values (the pipeline
//     copies u = 0 over u = m and a pole row's u = 0 over the row as a safety net);
//   * keep results finite and within +-ctx.heightLimit;
//   * return a seam-wrapped rectangle covering every vertex it changed (a superset is fine).
class Tool {
 public:
  virtual ~Tool() = default;

  virtual std::string name() const = 0;
  // Throws core::InputError naming the bad parameter and its value; called before anything is
  // touched.
  virtual void validate() const = 0;
  // r_d, the radius of the deformation area (m).
  virtual double radius() const = 0;
  // Arc length between stamps when the tool moves (m); a moving stroke stamps at this spacing so
  // a fast stroke leaves no gaps.
  virtual double spacing() const { return 0.25 * radius(); }
  // Rate tools act per second: a stroke sample that does not move still applies (for its dt).
  virtual bool rateBased() const { return false; }
  // The vertices apply() may write; by default V_d. A tool reaching further returns a region it
  // owns (built in apply's preparation; the pipeline calls footprint() right before apply()).
  virtual const Region& footprint(const ToolContext& ctx) const { return ctx.region; }
  // Whether footprint() is V_d (the default): the pipeline then reads V_d as the vertices an
  // apply() changed, to cut the error bounds' update to them, without asking footprint().
  virtual bool footprintIsRegion() const { return true; }
  // Called before a stroke's first stamp (and before a lone apply()): a tool that keeps state
  // between the stamps of a stroke (the TIN sand tool's region TIN) starts it afresh, so that a
  // stroke's result depends only on the heights at its start and its own samples (a journal or
  // a recording replayed from any stroke gives the same planet).
  virtual void beginStroke() const {}

  virtual terrain::VertexBox apply(const ToolContext& ctx, std::span<float> heights) const = 0;
};

}  // namespace ps::edit
