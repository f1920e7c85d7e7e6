#include "haptics/force_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/input_error.hpp"

namespace ps::haptics {

void PressSettings::validate(const core::Chart& chart) const {
  if (!(std::isfinite(yield) && yield > 0 && yield <= 1))
    throw core::InputError("haptics: press yield = " + std::to_string(yield) +
                           " must be in (0, 1]");
  if (!(std::isfinite(minDepth) && minDepth >= 0))
    throw core::InputError("haptics: press min depth = " + std::to_string(minDepth) +
                           " m must be finite and >= 0");
  if (maxStampsPerFrame < 1)
    throw core::InputError("haptics: max stamps per frame = " + std::to_string(maxStampsPerFrame) +
                           " must be >= 1");
  displacement.validate(&chart);
}

void ForcePathConfig::validate(const core::Chart& chart) const {
  haptics.validate();
  map.validate();
  if (!(std::isfinite(patchRadius) && patchRadius > 0 && patchRadius <= 1))
    throw core::InputError("haptics: patch radius = " + std::to_string(patchRadius) +
                           " m must be in (0, 1]");
  if (!(std::isfinite(trackerTimeout) && trackerTimeout > 0))
    throw core::InputError("haptics: tracker timeout = " + std::to_string(trackerTimeout) +
                           " s must be finite and > 0");
  press.validate(chart);
}

namespace {

const ForcePathConfig& checked(const ForcePathConfig& c, const core::Chart& chart) {
  c.validate(chart);
  return c;
}

// Grid cells (along v, the finest spacing on a lat-long chart) the snapshot must reach.
int halfSizeFor(const ForcePathConfig& c, const core::Chart& chart) {
  const double cell = sand::largestSpacing(chart);
  const double cells = std::ceil(c.patchRadius * c.map.scale / cell);
  return int(std::clamp(cells, 2.0, 1024.0));
}

}  // namespace

ForcePath::ForcePath(const terrain::Terrain& terrain, edit::EditPipeline* pipeline,
                     ForcePathConfig config, sand::EditListener* listener)
    : terrain_(terrain),
      pipeline_(pipeline),
      config_(checked(config, terrain.chart())),
      halfSize_(halfSizeFor(config_, terrain.chart())),
      tool_(terrain.chartPtr(), config_.press.displacement, listener),
      core_(config_.haptics, config_.map),
      marker_(config_.trackerTimeout) {
  if (pipeline_ && &pipeline_->terrain() != &terrain_)
    throw core::InputError("haptics: the edit pipeline edits another terrain");
}

ForcePath::~ForcePath() {
  stopLoop();
}

void ForcePath::focus(const Eigen::Vector3d& planetPoint) {
  if (!planetPoint.allFinite()) throw core::InputError("haptics: focus point is not finite");
  lastTip_ = planetPoint;
  haveTip_ = true;
  if (loop_) loop_->publishPatch(terrain_, lastTip_, halfSize_, surface_.get());
}

void ForcePath::setLog(std::ostream* csv) {
  writer_ = csv ? std::make_unique<ForceLogWriter>(*csv) : nullptr;
}

FrameForces ForcePath::onFrame(const std::optional<Eigen::Vector3d>& tipPlanet, double time) {
  if (loop_) throw core::InputError("haptics: onFrame while the live loop runs");
  FrameForces f;
  if (!std::isfinite(time)) {
    f.notes.push_back("frame time is not finite: frame skipped, forces zero");
    return f;
  }
  const double rate = config_.haptics.rateHz;
  const bool valid = tipPlanet && tipPlanet->allFinite();
  if (valid) {
    lastTip_ = *tipPlanet;
    haveTip_ = true;
  }
  if (haveTip_) {
    if (!patch_.capture(terrain_, lastTip_, halfSize_, surface_.get())) patch_.clear();
  }
  if (!started_) {
    nextTick_ = (long long)std::ceil(time * rate);
    started_ = true;
  }
  // A long gap (seek, stall) does not replay its ticks: at most one second of them.
  nextTick_ = std::max(nextTick_, (long long)std::ceil((time - 1.0) * rate));
  records_.clear();
  for (; double(nextTick_) / rate <= time; ++nextTick_) {
    const double t = double(nextTick_) / rate;
    Eigen::Vector3d pos = Eigen::Vector3d::Zero();
    const bool ok = marker_.read(t, pos);
    records_.push_back(core_.tick(t, ok, pos, patch_.valid() ? &patch_ : nullptr));
  }
  // As in the live loop, this frame's tip arrives at `time`: the ticks up to it ran on the
  // earlier samples (one frame late), the next frame's ticks move towards this one.
  // Not tracked: nothing pushed; the device holds the last tip until its timeout.
  if (valid) marker_.push(config_.map.toDevice(*tipPlanet), time);
  consume(records_, f);
  return f;
}

void ForcePath::startLoop(HapticDevice& device, LoopOptions options) {
  if (loop_) throw core::InputError("haptics: the live loop is already running");
  auto settings = config_.haptics;
  if (const auto lim = device.limits()) {  // the tighter of the device's and ours
    settings.limits.maxForce = std::min(settings.limits.maxForce, lim->maxForce);
    settings.limits.maxStiffness = std::min(settings.limits.maxStiffness, lim->maxStiffness);
    settings.limits.maxDamping = std::min(settings.limits.maxDamping, lim->maxDamping);
    settings.limits.maxForceRate = std::min(settings.limits.maxForceRate, lim->maxForceRate);
  }
  loop_ = std::make_unique<HapticLoop>(device, settings, config_.map, options);
  if (haveTip_) loop_->publishPatch(terrain_, lastTip_, halfSize_, surface_.get());
  loop_->start();
}

void ForcePath::stopLoop() {
  if (!loop_) return;
  loop_->stop();
  loop_.reset();
}

FrameForces ForcePath::editorFrame() {
  FrameForces f;
  if (!loop_) throw core::InputError("haptics: editorFrame without a running loop");
  records_.clear();
  loop_->drain(records_);
  consume(records_, f);
  // Snapshot around the newest tip (after this frame's edits), for the loop's next ticks.
  if (const auto l = loop_->latest(); l && l->tipPlanet.allFinite()) {
    lastTip_ = l->tipPlanet;
    haveTip_ = true;
  }
  if (haveTip_) loop_->publishPatch(terrain_, lastTip_, halfSize_, surface_.get());
  return f;
}

void ForcePath::consume(const std::vector<ForceRecord>& records, FrameForces& f) {
  Fault seen[6] = {};
  for (const ForceRecord& r : records) {
    ++f.ticks;
    if (r.touching) ++f.touchingTicks;
    f.maxForce = std::max(f.maxForce, r.force.norm());
    if (r.fault != Fault::kNone && seen[int(r.fault)] == Fault::kNone) {
      seen[int(r.fault)] = r.fault;
      f.notes.push_back(std::string("haptics: ") + toString(r.fault) +
                        " at t = " + std::to_string(r.time) + " s: force zero");
    }
    press(r, f);
  }
  if (!records.empty()) f.last = records.back();
  if (writer_) writer_->write(records);
}

void ForcePath::press(const ForceRecord& r, FrameForces& f) {
  const PressSettings& ps = config_.press;
  if (!pipeline_ || !ps.enabled) return;
  if (r.fault != Fault::kNone || !r.touching || !(r.depth > ps.minDepth)) {
    inContact_ = false;
    return;
  }
  const double radius = ps.displacement.radius;
  const double spacing = ps.displacement.spacing * radius;
  if (inContact_ && (r.tipPlanet - lastStamp_).norm() < spacing) return;
  if (f.stamps >= ps.maxStampsPerFrame) return;
  if (pipeline_->inStroke()) {
    if (f.notes.empty() || f.notes.back().find("stroke") == std::string::npos)
      f.notes.push_back("haptics: a stroke is open in the edit pipeline: press not applied");
    return;
  }
  // Depth against the live surface (earlier stamps may have lowered it since the snapshot).
  if (!probePatch_.capture(terrain_, r.tipPlanet, 2)) return;
  const auto s = probePatch_.probe(r.tipPlanet);
  if (!s || !(s->depth > 0)) {
    inContact_ = true;
    lastStamp_ = r.tipPlanet;
    return;
  }
  const Eigen::Vector3d centre = s->surface + (radius - ps.yield * s->depth) * s->up;
  try {
    pipeline_->apply(tool_, edit::ToolInput{centre, 0.0});
    ++f.stamps;
    ++totalStamps_;
  } catch (const core::InputError& e) {
    f.notes.push_back(std::string("haptics: press refused: ") + e.what());
  }
  inContact_ = true;
  lastStamp_ = r.tipPlanet;
}

}  // namespace ps::haptics
