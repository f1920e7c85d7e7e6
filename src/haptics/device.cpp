#include "haptics/device.hpp"

#include <algorithm>
#include <cmath>

#include "core/input_error.hpp"

namespace ps::haptics {

ScriptedDevice::Path ScriptedDevice::keyframes(
    std::vector<std::pair<double, Eigen::Vector3d>> frames) {
  if (frames.empty()) throw core::InputError("scripted device: no keyframes");
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (!(frames[i].first > frames[i - 1].first))
      throw core::InputError("scripted device: keyframe times must increase (keyframe " +
                             std::to_string(i) + ")");
  }
  return [frames = std::move(frames)](double t) -> std::optional<Eigen::Vector3d> {
    if (t <= frames.front().first) return frames.front().second;
    if (t >= frames.back().first) return frames.back().second;
    const auto it = std::upper_bound(frames.begin(), frames.end(), t,
                                     [](double x, const auto& f) { return x < f.first; });
    const auto& b = *it;
    const auto& a = *(it - 1);
    const double s = (t - a.first) / (b.first - a.first);
    return Eigen::Vector3d(a.second + s * (b.second - a.second));
  };
}

bool ScriptedDevice::read(double t, Eigen::Vector3d& position) noexcept {
  const auto p = path_(t);
  if (!p) return false;
  position = *p;
  return true;
}

void ScriptedDevice::command(const Eigen::Vector3d& force) noexcept {
  last_ = force;
  commands_.fetch_add(1, std::memory_order_relaxed);
}

TrackedMarkerDevice::TrackedMarkerDevice(double timeout) : timeout_(timeout) {
  if (!(std::isfinite(timeout) && timeout > 0))
    throw core::InputError("tracked marker device: timeout = " + std::to_string(timeout) +
                           " s must be finite and > 0");
}

void TrackedMarkerDevice::push(const Eigen::Vector3d& position, double t) {
  if (!position.allFinite() || !std::isfinite(t)) {
    writer_.count = 0;  // lost: the next sample starts afresh
  } else if (writer_.count > 0 && !(t > writer_.tb)) {
    return;  // not newer: ignored
  } else {
    writer_.a = writer_.b;
    writer_.ta = writer_.tb;
    writer_.b = position;
    writer_.tb = t;
    writer_.count = std::min(2, writer_.count + 1);
  }
  shared_.back() = writer_;
  shared_.publish();
}

bool TrackedMarkerDevice::read(double t, Eigen::Vector3d& position) noexcept {
  shared_.update();
  const Pair& p = shared_.front();
  if (p.count == 0 || !(t - p.tb <= timeout_)) return false;
  if (p.count == 1) {
    position = p.b;
    return true;
  }
  // One frame late: at t = tb we are at a, at t = tb + (tb - ta) at b.
  const double span = p.tb - p.ta;
  const double s = std::clamp((t - p.tb) / span, 0.0, 1.0);
  position = p.a + s * (p.b - p.a);
  return true;
}

}  // namespace ps::haptics
