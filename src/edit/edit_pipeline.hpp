#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <vector>

#include "core/grid.hpp"
#include "edit/distance_field.hpp"
#include "edit/region_growing.hpp"
#include "edit/tool.hpp"
#include "edit/undo_journal.hpp"
#include "terrain/terrain.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::edit {

// What one application of a tool (a stamp) did and cost.
struct EditReport {
  core::GridPoint control{};  // the control vertex (seam and poles as u = 0)
  std::size_t modifiedVertices =
      0;  // |V_d| in grid entries (seam twins and pole-row entries counted)
  std::size_t modifiedPoints = 0;  // |V_d| in distinct points of the sphere
  terrain::VertexBox dirty;        // what the bounds update was told
  std::size_t boundsVertices = 0;  // bound vertices the update recomputed
  double growMs = 0;               // control vertex + region growing
  double heightsMs = 0;            // the tool + seam/pole consistency
  double errorsMs = 0;             // Terrain::commitEdit (hierarchical bounds update)
  double journalMs = 0;            // undo snapshot and diff (0 with undo disabled)
  double totalMs = 0;
};

// Sum over the stamps of a stroke (or of one moveTo()).
struct StrokeReport {
  int stamps = 0;
  std::size_t modifiedVertices = 0;
  double growMs = 0, heightsMs = 0, errorsMs = 0, journalMs = 0, totalMs = 0;
  void add(const EditReport& r);
  void add(const StrokeReport& r);
};

// Sees every stroke before it changes the terrain (the stroke recorder of stroke_script.hpp).
// A callback may throw core::InputError to refuse; the terrain is then untouched.
class EditObserver {
 public:
  virtual ~EditObserver() = default;
  virtual void onBeginStroke(const Tool& tool, const ToolInput& start) = 0;
  virtual void onMoveStroke(const ToolInput& sample) = 0;
  virtual void onEndStroke() = 0;
  virtual void onUndo() = 0;
  virtual void onRedo() = 0;
};

// The edit pipeline (paper 003, section 6): tool position -> control vertex -> V_d by region
// growing -> the tool writes heights -> seam twins and pole rows made consistent -> hierarchical
// bounds update over the dirty region (Terrain::commitEdit) -> undo journal.
//
// Strokes: beginStroke() stamps at the start; moveTo() stamps along the path (a great circle on
// the reference sphere; a straight line on a flat chart) from the last stamp at intervals of
// tool.spacing() (r_d / 4 for the brush by default), so however far the tool jumped between two
// samples, consecutive stamps are at most one spacing apart and the stroke leaves no gaps; the
// remainder carries over to the next sample. A rate tool (rateBased()) instead spreads each
// sample's dt over max(1, ceil(arc / spacing)) equal steps ending at the sample, so held still it
// keeps acting per second, not per frame. One sample stamps at most kMaxStampsPerSample times:
// a jump longer than that many spacings (a tracking glitch; 1,024 r_d for the brush) is stamped
// at a stretched spacing of arc / kMaxStampsPerSample, so a teleport costs milliseconds, not
// seconds. A stroke is one undo step.
//
// Bad input (a tool that fails validate(), a non-finite dt or position, a position at the
// centre) throws core::InputError before anything changes.
class EditPipeline {
 public:
  static constexpr int kMaxStampsPerSample = 4096;

  explicit EditPipeline(terrain::Terrain& terrain);

  terrain::Terrain& terrain() { return terrain_; }
  const terrain::Terrain& terrain() const { return terrain_; }
  const DistanceField& field() const { return field_; }
  // V_d of the last stamp.
  const Region& lastRegion() const { return region_; }
  const EditReport& lastReport() const { return last_; }

  // One stamp as a stroke of its own (one undo step). Not allowed while a stroke is open.
  EditReport apply(const Tool& tool, const ToolInput& input);

  // `tool` must outlive the stroke.
  EditReport beginStroke(const Tool& tool, const ToolInput& start);
  EditReport beginStroke(const Tool&& tool, const ToolInput& start) = delete;  // would dangle
  StrokeReport moveTo(const ToolInput& sample);
  void endStroke();
  bool inStroke() const { return strokeTool_ != nullptr; }

  // Undo journal (on by default; off skips the snapshot and diff per stamp).
  void setUndoEnabled(bool on);
  bool undoEnabled() const { return undoEnabled_; }
  UndoJournal& journal() { return journal_; }
  const UndoJournal& journal() const { return journal_; }
  void undo();
  void redo();
  // Heights something else changed as a consequence of the strokes (sand settling): they join the
  // open or latest stroke's undo step (UndoJournal::recordOutside). Nothing when undo is off.
  void recordOutside(std::span<const HeightChange> changes, const terrain::VertexBox& dirty);

  void setObserver(EditObserver* observer) { observer_ = observer; }
  EditObserver* observer() const { return observer_; }

  // Throws core::InputError unless the tool validates and the input is usable; touches nothing.
  void validate(const Tool& tool, const ToolInput& input) const;

 private:
  EditReport stamp(const Tool& tool, const ToolInput& input);
  // Stroke paths: great circles (radius() > 0; arc length measured on the reference sphere, the
  // distance from the centre interpolated linearly), straight lines otherwise.
  double pathLength(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
  Eigen::Vector3d pathAt(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double t) const;

  terrain::Terrain& terrain_;
  DistanceField field_;
  RegionGrower grower_;
  Region region_;
  float heightLimit_;
  EditReport last_;

  bool undoEnabled_ = true;
  UndoJournal journal_;
  std::vector<float> snapshot_;

  const Tool* strokeTool_ = nullptr;
  Eigen::Vector3d lastStamp_ = Eigen::Vector3d::Zero();  // where the last stamp was applied
  EditObserver* observer_ = nullptr;
};

// Great-circle interpolation between unit vectors a and b (t in [0, 1]); antipodal inputs turn
// about an arbitrary perpendicular axis.
Eigen::Vector3d slerpUnit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double t);

}  // namespace ps::edit
