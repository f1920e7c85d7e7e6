#pragma once
// Stroke files: scripted sculpting, and the journal that replays a session onto a planet.
//
// Text, one command per line; '#' starts a comment (to the end of the line); blank lines are
// ignored; tokens are separated by spaces or tabs.
//
//   brush KEY=VALUE ...   change the brush; keys not named keep their value. Keys:
//                           r_km / r_m     radius of deformation r_d (km / m), > 0
//                           sigma          Gaussian sigma, > 0 (paper 003: 0.17, 0.75)
//                           mu             Gaussian mu, > 0.5 (paper 003: 1)
//                           mode           raise | lower | set
//                           strength_m     change at the control vertex per stamp (m), >= 0
//                           rate_mps       makes it a rate brush: change per second (m/s), >= 0
//                           target_m       height that mode=set moves toward (m)
//                           spacing        stroke stamp spacing as a fraction of r_d, (0, 1]
//                         Defaults: r_km=300 sigma=0.17 mu=1 mode=raise strength_m=1000 target_m=0
//                         spacing=0.25. Not allowed inside a stroke.
//   stamp POINT [dt=S]    one stamp (one undo step)
//   stroke POINT [dt=S]   begin a stroke with a stamp at POINT
//   to POINT [dt=S]       move the tool within the stroke: stamps along the way every spacing
//   end                   end the stroke (the whole stroke is one undo step)
//   undo [N]              take back the last N strokes/stamps (default 1)
//   redo [N]
//
// POINT is either `LAT LON` in degrees (latitude -90..90, longitude -360..360; the seam u = 0 is
// longitude -180, the north pole latitude 90) on the reference sphere (lat-long and octahedral
// planets only: a torus, a cylinder or a flat grid has none), or `xyz=X,Y,Z`, a point of
// the planet frame in metres (what the recorder writes, so a replay is bit-for-bit). dt is in
// seconds (default 0) and matters only for rate brushes.
//
// A script is parsed and validated completely before the planet is touched; any problem throws
// core::InputError "FILE:LINE: what is wrong (naming the value)" and leaves the planet exactly
// as it was. See docs/EDITING.md.
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"

namespace ps::edit {

struct ScriptPoint {
  bool xyz = false;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();  // (lat deg, lon deg, 0) or (x, y, z) m
};

struct ScriptCommand {
  enum class Kind { kBrush, kStamp, kStroke, kTo, kEnd, kUndo, kRedo };
  Kind kind = Kind::kStamp;
  int line = 0;
  BrushSettings brush;  // kBrush: the complete settings from this line on
  ScriptPoint point;    // kStamp, kStroke, kTo
  double dt = 0.0;
  int count = 1;  // kUndo, kRedo
};

struct StrokeScript {
  std::string source = "<script>";
  std::vector<ScriptCommand> commands;
  // The script as text in the format above (numbers with 17 significant digits).
  std::string toText() const;
};

// Throws core::InputError "SOURCE:LINE: ..." for a syntax error or a bad value.
StrokeScript parseStrokeScript(std::string_view text, const std::string& source = "<script>");
StrokeScript loadStrokeScript(const std::filesystem::path& path);

// A script point's position in the planet frame on a sphere of `radius` metres.
Eigen::Vector3d scriptPosition(const ScriptPoint& p, double radius);

// Checks everything a run needs (structure, points, undo depth against the pipeline's journal)
// without touching the planet. Throws core::InputError "SOURCE:LINE: ...".
void validateStrokeScript(const StrokeScript& script, const EditPipeline& pipeline);

struct ScriptRunReport {
  int strokes = 0;  // strokes and single stamps
  int undos = 0, redos = 0;
  StrokeReport edits;
};
// Validates, then runs the whole script through the pipeline.
ScriptRunReport runStrokeScript(const StrokeScript& script, EditPipeline& pipeline);

// The stroke journal: attached to a pipeline (EditPipeline::setObserver), it writes down every
// stroke, stamp, undo and redo as script commands; replaying script() with runStrokeScript on
// the starting planet rebuilds the same heights bit for bit. Only the Gaussian brush can be
// recorded; another tool is refused (InputError) before it changes anything.
class StrokeRecorder final : public EditObserver {
 public:
  explicit StrokeRecorder(std::string source = "<journal>") { script_.source = std::move(source); }
  const StrokeScript& script() const { return script_; }
  void clear();

  void onBeginStroke(const Tool& tool, const ToolInput& start) override;
  void onMoveStroke(const ToolInput& sample) override;
  void onEndStroke() override;
  void onUndo() override;
  void onRedo() override;

 private:
  void push(ScriptCommand c);

  StrokeScript script_;
  bool haveBrush_ = false;
  BrushSettings brush_;
  bool open_ = false;
  std::size_t openIndex_ = 0;  // the stroke's first command
  bool moved_ = false;
};

}  // namespace ps::edit
