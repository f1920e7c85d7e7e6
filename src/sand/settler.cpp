#include "sand/settler.hpp"

#include <chrono>
#include <cmath>

#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "edit/brush.hpp"

namespace ps::sand {

namespace {
using Clock = std::chrono::steady_clock;
double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

constexpr core::NameTable<SettleMethod, 3> kSettleMethods{
    "settling method",
    {{{SettleMethod::kThermal, "thermal"},
      {SettleMethod::kDiffusionExplicit, "diffusion-explicit"},
      {SettleMethod::kDiffusionSemiImplicit, "diffusion-implicit"}}}};
}  // namespace

std::string toString(SettleMethod method) {
  return kSettleMethods.nameOf(method);
}

SettleMethod settleMethodFromString(const std::string& s) {
  return kSettleMethods.parse(s);
}

void SettleSettings::validate() const {
  if (cellBudget < 1) throw core::InputError("cell budget must be >= 1 cell-step per frame");
  if (maxStepsPerFrame < 1) {
    throw core::InputError("max steps per frame = " + std::to_string(maxStepsPerFrame) +
                           " must be >= 1");
  }
  if (!std::isfinite(diffusionDt) || !(diffusionDt > 0.0)) {
    throw core::InputError("diffusion dt = " + core::exactNumber(diffusionDt) +
                           " must be finite and > 0");
  }
  if (method != SettleMethod::kThermal && method != SettleMethod::kDiffusionExplicit &&
      method != SettleMethod::kDiffusionSemiImplicit) {
    throw core::InputError("settling method " + std::to_string(int(method)) + " is unknown");
  }
}

Settler::Settler(terrain::Terrain& terrain, Material material, SettleSettings settings)
    : terrain_(terrain),
      field_(terrain.chartPtr(), terrain.mutableHeights()),
      material_(std::move(material)),
      settings_(settings),
      expectedRevision_(terrain.revision()),
      limit_(edit::floatAtMost(terrain.heightLimit())) {
  material_.validate();
  settings_.validate();
}

void Settler::edited(const terrain::VertexBox& region, const Material& material) {
  material.validate();
  material_ = material;
  if (!region.empty()) pending_.push_back(region);
}

void Settler::settleAll() {
  field_.markAll();
}

void Settler::setMaterial(const Material& material) {
  material.validate();
  material_ = material;
}

void Settler::setSettings(const SettleSettings& settings) {
  settings.validate();
  settings_ = settings;
}

FrameReport Settler::frame() {
  FrameReport rep;
  const auto t0 = Clock::now();
  // Heights changed outside: what the field holds is re-read where it differs (and settles
  // there); the reported regions settle.
  if (terrain_.revision() != expectedRevision_) field_.resync();
  for (const terrain::VertexBox& r : pending_) field_.mark(r);
  pending_.clear();
  const PushForce* force = force_ ? &*force_ : nullptr;
  while (rep.steps < settings_.maxStepsPerFrame && (!field_.atRest() || force)) {
    StepReport s;
    switch (settings_.method) {
      case SettleMethod::kThermal:
        s = field_.thermalStep(material_);
        break;
      case SettleMethod::kDiffusionExplicit:
        s = field_.diffusionStep(material_, settings_.diffusionDt, DiffusionScheme::kExplicit,
                                 StepPolicy::kClamp, force);
        break;
      case SettleMethod::kDiffusionSemiImplicit:
        s = field_.diffusionStep(material_, settings_.diffusionDt, DiffusionScheme::kSemiImplicit,
                                 StepPolicy::kClamp, force);
        break;
    }
    ++rep.steps;
    rep.cellSteps += s.cells;
    // Whole steps only: stop when another step of this size would exceed the budget.
    if (rep.cellSteps + s.cells > settings_.cellBudget) break;
  }
  const auto t1 = Clock::now();
  changes_.clear();
  rep.dirty = field_.writeBack(limit_, undo_ ? &changes_ : nullptr);
  const auto t2 = Clock::now();
  if (!rep.dirty.empty()) {
    terrain_.commitEdit(rep.dirty);
    rep.boundsVertices = terrain_.bounds().lastUpdateVertexCount();
  }
  if (undo_ && !changes_.empty()) undo_->recordOutside(changes_, rep.dirty);
  expectedRevision_ = terrain_.revision();
  const auto t3 = Clock::now();
  rep.atRest = atRest();
  rep.simulateMs = ms(t0, t1);
  rep.writeMs = ms(t1, t2);
  rep.boundsMs = ms(t2, t3);
  rep.totalMs = ms(t0, t3);
  return rep;
}

}  // namespace ps::sand
