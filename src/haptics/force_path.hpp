#pragma once
// The editor-side face of the haptic path: what the app and the replay call.
//
// * Offline (replay, tests): onFrame(tipPlanet, time) once per video frame. The tip goes into a
//   TrackedMarkerDevice; the haptic ticks between the previous frame and `time` run right there
//   at the fixed rate (simulated time t_k = k / rate, so the force log is the same on every run),
//   then their records go to the force log and drive the sand displacement.
// * Live: startLoop(device) runs a HapticLoop thread; the editor calls editorFrame() once per
//   rendered frame: it drains the loop's records (log, arrow, presses), applies the presses
//   through the edit pipeline and publishes a fresh terrain snapshot around the tool.
//
// Presses: while the tip is below the surface, a DisplacementTool stamp (paper 004's sphere) is
// applied through edit::EditPipeline::apply with the sphere's bottom `yield` x depth below the
// live surface: deeper pushes move more sand. A new stamp when the tip has moved `spacing` x
// radius since the last one (and at first contact). Only ever on the editor thread.
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "edit/edit_pipeline.hpp"
#include "haptics/device.hpp"
#include "haptics/force_log.hpp"
#include "haptics/haptic_core.hpp"
#include "haptics/haptic_loop.hpp"
#include "sand/displacement.hpp"
#include "sand/listener.hpp"
#include "terrain/terrain.hpp"

namespace ps::haptics {

struct PressSettings {
  bool enabled = true;
  sand::DisplacementSettings displacement;  // radius in planet metres (default 100 km)
  double yield = 0.5;                       // (0, 1]: fraction of the tip's depth a stamp carves
  double minDepth = 0.0;      // device metres (>= 0): shallower contact does not stamp
  int maxStampsPerFrame = 8;  // >= 1: bounds the editor's work per frame
  void validate(const core::Chart& chart) const;
};

struct ForcePathConfig {
  HapticSettings haptics;
  WorkspaceMap map;             // scale = planet metres per device metre
  double patchRadius = 0.01;    // device metres of terrain around the tip in each snapshot
  double trackerTimeout = 0.2;  // s without a tip = the marker device stops answering
  PressSettings press;
  void validate(const core::Chart& chart) const;  // core::InputError naming the parameter
};

// What one frame's ticks did.
struct FrameForces {
  int ticks = 0;
  int touchingTicks = 0;
  double maxForce = 0;              // N over the frame's ticks
  std::optional<ForceRecord> last;  // the newest tick: the AR view's force arrow
  int stamps = 0;                   // displacement stamps applied
  std::vector<std::string> notes;   // faults (first of each kind), refused edits
};

class ForcePath {
 public:
  // `pipeline` may be null (forces only, no sculpting: e.g. from replay's read-only frame hook);
  // otherwise it must edit `terrain`. `listener` (e.g. a sand::Settler) is told what the
  // displacement changed. All must outlive the force path.
  ForcePath(const terrain::Terrain& terrain, edit::EditPipeline* pipeline, ForcePathConfig config,
            sand::EditListener* listener = nullptr);
  ~ForcePath();

  // Force log (CSV, force_log.hpp) from now on; nullptr stops logging. Editor thread.
  void setLog(std::ostream* csv);
  std::size_t logRows() const { return writer_ ? writer_->rows() : 0; }

  // Offline: the tool tip of one frame (planet frame, planet metres; nullopt = not tracked) at
  // `time` (s, increasing).
  FrameForces onFrame(const std::optional<Eigen::Vector3d>& tipPlanet, double time);

  // Live. The device must outlive the loop.
  void startLoop(HapticDevice& device, LoopOptions options = {});
  FrameForces editorFrame();
  void stopLoop();
  HapticLoop* loop() { return loop_.get(); }

  // A surface of its own over part of the terrain, felt in place of the grid's where the tip's
  // foot point lies in it (the sand TIN's region: replay::FrameStepper::viewPatch, which is
  // null once the grid no longer holds what the region wrote); null: the grid alone. Its
  // triangles near the tool are copied into each snapshot, so it may change between frames.
  // Editor thread, before onFrame / editorFrame.
  void setSurface(std::shared_ptr<const terrain::MeshPatch> surface) {
    surface_ = std::move(surface);
  }

  // Where the tool is expected before the device has reported (the first snapshot is taken
  // around it). Editor thread.
  void focus(const Eigen::Vector3d& planetPoint);

  const ForcePathConfig& config() const { return config_; }
  int patchHalfSize() const { return halfSize_; }
  std::uint64_t totalStamps() const { return totalStamps_; }

 private:
  void consume(const std::vector<ForceRecord>& records, FrameForces& f);
  void press(const ForceRecord& r, FrameForces& f);

  const terrain::Terrain& terrain_;
  edit::EditPipeline* pipeline_;
  ForcePathConfig config_;
  int halfSize_;
  sand::DisplacementTool tool_;

  // offline
  HapticCore core_;
  TrackedMarkerDevice marker_;
  TerrainPatch patch_;
  bool started_ = false;
  long long nextTick_ = 0;
  Eigen::Vector3d lastTip_ = Eigen::Vector3d::Zero();
  bool haveTip_ = false;

  // live
  std::unique_ptr<HapticLoop> loop_;

  std::shared_ptr<const terrain::MeshPatch> surface_;

  // presses
  TerrainPatch probePatch_;
  bool inContact_ = false;
  Eigen::Vector3d lastStamp_ = Eigen::Vector3d::Zero();

  std::unique_ptr<ForceLogWriter> writer_;
  std::vector<ForceRecord> records_;
  std::uint64_t totalStamps_ = 0;
};

}  // namespace ps::haptics
