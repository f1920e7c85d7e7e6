#include "edit/edit_pipeline.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "core/input_error.hpp"
#include "edit/brush.hpp"
#include "edit/control_vertex.hpp"
#include "edit/grid_consistency.hpp"

namespace ps::edit {

namespace {
using Clock = std::chrono::steady_clock;
double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// The dirty box's images across glued sides (terrain::gluedImages), each cut to the diagonals
// around the footprint's vertices inside it (terrain::Diagonals): every vertex apply() changed
// is in the footprint and in one of the images, so in that image's cut. On the octahedral
// chart a disc about a pole is a triangle in each image, or a diamond, half its box. Open cuts
// without a footprint, and on charts with a u seam (their columns wrap).
std::vector<terrain::CutBox> cutImages(const core::Chart& chart, const terrain::VertexBox& dirty,
                                       const Region* footprint) {
  std::vector<terrain::CutBox> out;
  for (const terrain::VertexBox& box : terrain::gluedImages(chart, dirty)) {
    terrain::Diagonals cut;
    if (footprint && !chart.wrapsU()) {
      cut = terrain::Diagonals::nothing();
      const int vLast = std::min(box.vEnd, footprint->vEnd());
      for (int v = std::max(box.vBegin, footprint->vBegin()); v <= vLast; ++v) {
        for (const Span& s : footprint->row(v)) {
          const int a = std::max(s.uBegin, box.uBegin), b = std::min(s.uEnd, box.uEnd);
          if (a > b) continue;
          cut.add(a, v);
          cut.add(b, v);
        }
      }
    }
    out.push_back({box, cut});
  }
  return out;
}

}  // namespace

namespace {

// The vertices and times of a stamp's report (EditReport) or a stroke's (StrokeReport) added to
// a stroke's.
template <class Report>
void addCounts(StrokeReport& to, const Report& r) {
  to.modifiedVertices += r.modifiedVertices;
  to.growMs += r.growMs;
  to.heightsMs += r.heightsMs;
  to.errorsMs += r.errorsMs;
  to.journalMs += r.journalMs;
  to.totalMs += r.totalMs;
}

}  // namespace

void StrokeReport::add(const EditReport& r) {
  ++stamps;
  addCounts(*this, r);
}

void StrokeReport::add(const StrokeReport& r) {
  stamps += r.stamps;
  addCounts(*this, r);
}

Eigen::Vector3d slerpUnit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double t) {
  const Eigen::Vector3d cross = a.cross(b);
  const double s = cross.norm(), c = a.dot(b);
  const double theta = std::atan2(s, c);
  if (theta < 1e-15) return a;
  Eigen::Vector3d axis;
  if (s > 1e-12) {
    axis = cross / s;
  } else {  // antipodal: any axis perpendicular to a
    axis = a.unitOrthogonal();
  }
  const double phi = t * theta;
  return (a * std::cos(phi) + axis.cross(a) * std::sin(phi)).normalized();
}

EditPipeline::EditPipeline(terrain::Terrain& terrain)
    : terrain_(terrain),
      field_(terrain.chartPtr()),
      heightLimit_(floatAtMost(terrain.heightLimit())) {}

void EditPipeline::setUndoEnabled(bool on) {
  if (inStroke()) throw core::InputError("cannot switch undo on or off during a stroke");
  undoEnabled_ = on;
  if (!on) journal_.clear();
}

void EditPipeline::validate(const Tool& tool, const ToolInput& input) const {
  tool.validate();
  const double r = tool.radius();
  if (!std::isfinite(r) || !(r > 0.0)) {
    throw core::InputError("radius of deformation r_d = " + core::exactNumber(r) +
                           " m must be finite and > 0");
  }
  const double sp = tool.spacing();
  if (!std::isfinite(sp) || !(sp > 0.0)) {
    throw core::InputError("stroke spacing " + core::exactNumber(sp) + " m must be finite and > 0");
  }
  if (!std::isfinite(input.dt) || input.dt < 0.0) {
    throw core::InputError("dt = " + core::exactNumber(input.dt) + " s must be finite and >= 0");
  }
  (void)nearestVertex(terrain_.chart(), input.position);  // throws for a bad position
}

EditReport EditPipeline::stamp(const Tool& tool, const ToolInput& input) {
  EditReport rep;
  const auto t0 = Clock::now();
  const core::Chart& chart = terrain_.chart();
  const core::GridSize g = chart.grid();
  field_.setCentre(nearestVertex(chart, input.position));
  grower_.grow(field_, tool.radius(), region_);
  const auto t1 = Clock::now();

  const RowDistanceBlocks* distances = grower_.distances();
  const ToolContext ctx{terrain_, field_, region_, field_.centre(), input, heightLimit_, distances};
  auto heights = terrain_.mutableHeights();
  const Region* footprint = nullptr;
  if (undoEnabled_) {
    footprint = &tool.footprint(ctx);
    snapshot_.resize(footprint->vertexCount());
    std::size_t i = 0;
    footprint->forEachSpan([&](int v, int a, int b) {
      std::memcpy(snapshot_.data() + i, heights.data() + g.index(a, v),
                  std::size_t(b - a + 1) * sizeof(float));
      i += std::size_t(b - a + 1);
    });
  }
  const auto t2 = Clock::now();
  const terrain::VertexBox dirty = tool.apply(ctx, heights);
  enforceConsistency(chart, heights, dirty);
  const auto t3 = Clock::now();
  if (undoEnabled_) journal_.recordStamp(*footprint, snapshot_, heights, g, dirty, chart.wrapsU());
  const auto t4 = Clock::now();
  if (!footprint && tool.footprintIsRegion()) footprint = &region_;
  terrain_.commitEdit(cutImages(chart, dirty, footprint));
  const auto t5 = Clock::now();

  rep.control = field_.centre();
  rep.modifiedVertices = region_.vertexCount();
  rep.modifiedPoints = region_.pointCount();
  rep.dirty = dirty;
  rep.boundsVertices = dirty.empty() ? 0 : terrain_.bounds().lastUpdateVertexCount();
  rep.growMs = ms(t0, t1);
  rep.heightsMs = undoEnabled_ ? ms(t2, t3) : ms(t1, t3);
  rep.journalMs = undoEnabled_ ? ms(t1, t2) + ms(t3, t4) : 0.0;
  rep.errorsMs = ms(t4, t5);
  rep.totalMs = ms(t0, t5);
  last_ = rep;
  return rep;
}

EditReport EditPipeline::apply(const Tool& tool, const ToolInput& input) {
  if (inStroke())
    throw core::InputError("apply() while a stroke is open: use moveTo() or end the stroke first");
  validate(tool, input);
  if (observer_) {
    observer_->onBeginStroke(tool, input);
    observer_->onEndStroke();
  }
  if (undoEnabled_) journal_.beginStroke();
  tool.beginStroke();
  const EditReport rep = stamp(tool, input);
  if (undoEnabled_) journal_.endStroke(terrain_.grid());
  return rep;
}

EditReport EditPipeline::beginStroke(const Tool& tool, const ToolInput& start) {
  if (inStroke())
    throw core::InputError("a stroke is already open: end it before beginning another");
  validate(tool, start);
  if (observer_) observer_->onBeginStroke(tool, start);
  if (undoEnabled_) journal_.beginStroke();
  strokeTool_ = &tool;
  lastStamp_ = start.position;
  tool.beginStroke();
  return stamp(tool, start);
}

StrokeReport EditPipeline::moveTo(const ToolInput& sample) {
  if (!inStroke()) throw core::InputError("moveTo outside a stroke: call beginStroke first");
  const Tool& tool = *strokeTool_;
  validate(tool, sample);
  if (observer_) observer_->onMoveStroke(sample);
  StrokeReport rep;
  const Eigen::Vector3d from = lastStamp_, to = sample.position;
  const double arc = pathLength(from, to);
  // A jump of more than kMaxStampsPerSample spacings (a tracking glitch, a tiny brush) stamps
  // kMaxStampsPerSample times evenly, the last at the sample: the work of one sample stays
  // bounded and nothing is left over for the next.
  const double spacing = tool.spacing();
  const bool stretched = arc > spacing * kMaxStampsPerSample;
  if (tool.rateBased() || stretched) {
    const int n = stretched ? kMaxStampsPerSample : int(std::max(1.0, std::ceil(arc / spacing)));
    for (int i = 1; i <= n; ++i)
      rep.add(stamp(tool, ToolInput{pathAt(from, to, double(i) / n), sample.dt / n}));
    lastStamp_ = to;
    return rep;
  }
  const int n = int(std::floor(arc / spacing));
  for (int i = 1; i <= n; ++i) {
    const Eigen::Vector3d p = pathAt(from, to, double(i) * spacing / arc);
    rep.add(stamp(tool, ToolInput{p, sample.dt / n}));
    lastStamp_ = p;
  }
  return rep;
}

double EditPipeline::pathLength(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  const double R = terrain_.chart().sphereRadius();
  if (R > 0.0) return R * std::atan2(a.cross(b).norm(), a.dot(b));
  return (b - a).norm();
}

Eigen::Vector3d EditPipeline::pathAt(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     double t) const {
  const double R = terrain_.chart().sphereRadius();
  // The distance from the centre is interpolated too: a tool held above or below the surface
  // (the displacement sphere) keeps its altitude along the stroke.
  if (R > 0.0)
    return (a.norm() + t * (b.norm() - a.norm())) * slerpUnit(a.normalized(), b.normalized(), t);
  return a + t * (b - a);
}

void EditPipeline::endStroke() {
  if (!inStroke()) throw core::InputError("endStroke without an open stroke");
  if (observer_) observer_->onEndStroke();
  strokeTool_ = nullptr;
  if (undoEnabled_) journal_.endStroke(terrain_.grid());
}

namespace {

// Throws InputError naming why an undo or a redo (`what`) cannot run: a stroke open, undo off,
// nothing journalled to take back (`available` strokes).
void checkJournalMove(const char* what, bool inStroke, bool undoEnabled, std::size_t available) {
  if (inStroke) throw core::InputError(std::string("cannot ") + what + " while a stroke is open");
  if (!undoEnabled) throw core::InputError("undo is disabled on this edit pipeline");
  if (available == 0) throw core::InputError(std::string("nothing to ") + what);
}

}  // namespace

void EditPipeline::undo() {
  checkJournalMove("undo", inStroke(), undoEnabled_, journal_.undoCount());
  if (observer_) observer_->onUndo();
  journal_.undo(terrain_);
}

void EditPipeline::recordOutside(std::span<const HeightChange> changes,
                                 const terrain::VertexBox& dirty) {
  if (!undoEnabled_) return;
  journal_.recordOutside(changes, terrain_.grid(), dirty, terrain_.chart().wrapsU());
}

void EditPipeline::redo() {
  checkJournalMove("redo", inStroke(), undoEnabled_, journal_.redoCount());
  if (observer_) observer_->onRedo();
  journal_.redo(terrain_);
}

}  // namespace ps::edit
