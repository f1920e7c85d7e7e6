#pragma once
// One haptic tick from a device reading: device -> planet frame -> depth under the tool in the
// terrain snapshot -> ForceModel. Shared by the real-time loop (HapticLoop) and the offline,
// deterministic stepping a replay uses (ForcePath::onFrame).
#include <Eigen/Core>

#include "haptics/force_model.hpp"
#include "haptics/settings.hpp"
#include "haptics/terrain_patch.hpp"

namespace ps::haptics {

// One tick as logged (CSV row of the force log, see force_log.hpp).
struct ForceRecord {
  double time = 0;                                      // s
  Eigen::Vector3d tipPlanet = Eigen::Vector3d::Zero();  // planet frame (planet m); NaN if none
  Eigen::Vector3d force = Eigen::Vector3d::Zero();      // device frame (N)
  double depth = 0;    // below the surface (device m); 0 when no contact was found
  double repulse = 0;  // N
  double damping = 0;  // N s/m
  double ramp = 0;
  bool touching = false;
  Fault fault = Fault::kNone;
};

class HapticCore {
 public:
  HapticCore(const HapticSettings& settings, const WorkspaceMap& map);  // validates both

  // `patch` may be null (none published yet).
  ForceRecord tick(double time, bool deviceOk, const Eigen::Vector3d& devicePosition,
                   const TerrainPatch* patch);
  void reset() {
    model_.reset();
    lastTouching_ = false;
    offset_ = 0;
  }

  const ForceModel& model() const { return model_; }
  const WorkspaceMap& map() const { return map_; }

 private:
  ForceModel model_;
  WorkspaceMap map_;
  // Blending a new snapshot's depth in (SafetySettings::surfaceBlendTime).
  std::uint64_t lastSerial_ = 0;
  bool lastTouching_ = false;
  double lastDepth_ = 0, lastTime_ = 0, offset_ = 0, offsetRate_ = 0;
  Eigen::Vector3d lastPos_ = Eigen::Vector3d::Zero();
};

}  // namespace ps::haptics
