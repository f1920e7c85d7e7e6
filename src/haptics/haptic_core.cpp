#include "haptics/haptic_core.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ps::haptics {

namespace {
constexpr double kMaxOffset = 0.005;  // m (device): larger differences are not blended
WorkspaceMap validated(const WorkspaceMap& m) {
  m.validate();
  return m;
}
}  // namespace

HapticCore::HapticCore(const HapticSettings& settings, const WorkspaceMap& map)
    : model_(settings), map_(validated(map)) {}

ForceRecord HapticCore::tick(double time, bool deviceOk, const Eigen::Vector3d& devicePosition,
                             const TerrainPatch* patch) {
  TickInput in;
  in.time = time;
  in.deviceOk = deviceOk;
  in.position = devicePosition;
  ForceRecord r;
  r.tipPlanet.setConstant(std::numeric_limits<double>::quiet_NaN());
  if (deviceOk && devicePosition.allFinite()) {
    r.tipPlanet = map_.toPlanet(devicePosition);
    if (patch && patch->valid()) {
      if (const auto s = patch->probe(r.tipPlanet)) {
        in.contact.valid = true;
        in.contact.normal = (map_.rotation.transpose() * s->up).normalized();
        const double raw = s->depth / map_.scale;
        const double dt = std::clamp(time - lastTime_, 0.0, 4 * model_.settings().period());
        const double blend = model_.settings().safety.surfaceBlendTime;
        if (patch->serial() != lastSerial_ && lastTouching_ && blend > 0) {
          // Where the old surface would put the tip now, minus where the new one does.
          const double predicted = lastDepth_ - in.contact.normal.dot(devicePosition - lastPos_);
          offset_ = std::clamp(predicted - raw, -kMaxOffset, kMaxOffset);
          offsetRate_ = std::abs(offset_) / blend;
        } else {
          const double step = offsetRate_ * dt;
          offset_ = std::abs(offset_) <= step ? 0.0 : offset_ - std::copysign(step, offset_);
        }
        lastSerial_ = patch->serial();
        in.contact.depth = raw + offset_;
      }
    }
  }
  const TickOutput o = model_.tick(in);
  if (o.fault != Fault::kNone || !in.contact.valid) {
    lastTouching_ = false;
    offset_ = 0;
  } else {
    lastTouching_ = o.touching;
    lastDepth_ = in.contact.depth;
  }
  lastTime_ = time;
  lastPos_ = devicePosition;
  r.time = time;
  r.force = o.force;
  r.depth = o.depth;
  r.repulse = o.repulse;
  r.damping = o.damping;
  r.ramp = o.ramp;
  r.touching = o.touching;
  r.fault = o.fault;
  return r;
}

}  // namespace ps::haptics
