#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "edit/edit_pipeline.hpp"
#include "sand/listener.hpp"
#include "sand/material.hpp"
#include "sand/sand_field.hpp"
#include "terrain/terrain.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::sand {

enum class SettleMethod {
  kThermal,                // paper 004's thermal erosion to the talus angle
  kDiffusionExplicit,      // paper 002's drift-diffusion, forward Euler at its stable dt
  kDiffusionSemiImplicit,  // the same, LOD implicit sweeps (any dt)
};
std::string toString(SettleMethod method);
SettleMethod settleMethodFromString(const std::string& s);  // throws core::InputError

struct SettleSettings {
  SettleMethod method = SettleMethod::kThermal;
  // Cell-steps one frame may spend (steps run whole: a frame runs steps until the next would
  // exceed the budget, and at least one). >= 1.
  std::size_t cellBudget = std::size_t(1) << 20;
  int maxStepsPerFrame = 256;  // >= 1
  // Diffusion: time per step (paper 002's frame units); the explicit scheme clamps it to its
  // stability bound. Finite, > 0.
  double diffusionDt = 0.25;

  void validate() const;  // throws core::InputError naming the bad field
};

// What one frame of settling did.
struct FrameReport {
  int steps = 0;
  std::size_t cellSteps = 0;
  terrain::VertexBox dirty;  // floats that changed (what Terrain::commitEdit was told)
  std::size_t boundsVertices = 0;
  bool atRest = false;
  double simulateMs = 0, writeMs = 0, boundsMs = 0, totalMs = 0;
};

// The settling step of the edit pipeline: after tools changed the terrain, material settles by
// gravity over the following frames, a budget of cell-steps per frame, so the live app keeps its
// frame rate while a crater settles. Each frame:
//   1. picks up the regions tools reported (edited()) and, when the terrain's revision changed
//      behind its back (another tool, undo), re-reads the cells it holds that differ;
//   2. runs whole steps of the current material's method while the budget lasts;
//   3. writes the changed floats back and calls Terrain::commitEdit over exactly the rectangle
//      of floats that changed: the error bounds are updated there only.
// With attachUndo(pipeline), what settling changes joins the undo step of the stroke it
// follows (edit::EditPipeline::recordOutside): undoing a sand stroke takes its settling back too.
class Settler final : public EditListener {
 public:
  explicit Settler(terrain::Terrain& terrain, Material material = Material::sand(),
                   SettleSettings settings = {});

  // From a tool (or the app): `region` changed and settles as `material` from now on.
  void edited(const terrain::VertexBox& region, const Material& material) override;
  // Settle everything (e.g. a terrain loaded from a file).
  void settleAll();

  void setMaterial(const Material& material);
  const Material& material() const { return material_; }
  void setSettings(const SettleSettings& settings);
  const SettleSettings& settings() const { return settings_; }
  // A drift force (paper 002) applied during diffusion frames until cleared.
  void setForce(std::optional<PushForce> force) { force_ = force; }

  // The pipeline whose undo journal records each frame's changes (nullptr: none). It must
  // outlive the settler or be detached first.
  void attachUndo(edit::EditPipeline* pipeline) { undo_ = pipeline; }

  FrameReport frame();
  bool atRest() const { return pending_.empty() && field_.atRest(); }

  SandField& field() { return field_; }
  const SandField& field() const { return field_; }

 private:
  terrain::Terrain& terrain_;
  SandField field_;
  Material material_;
  SettleSettings settings_;
  std::optional<PushForce> force_;
  edit::EditPipeline* undo_ = nullptr;
  std::vector<edit::HeightChange> changes_;  // a frame's write-back, for undo_
  std::vector<terrain::VertexBox> pending_;
  std::uint64_t expectedRevision_ = 0;
  float limit_ = 0;
};

}  // namespace ps::sand
