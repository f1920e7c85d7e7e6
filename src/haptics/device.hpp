#pragma once
// Haptic devices: what the loop reads the tool tip from and sends forces to. A real driver
// (CHAI3D, Force Dimension SDK, OpenHaptics) implements HapticDevice; docs/HAPTICS.md says how.
#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "haptics/settings.hpp"
#include "haptics/triple_buffer.hpp"

namespace ps::haptics {

class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  virtual std::string name() const = 0;
  // Whether command() reaches a motor (false: forces are computed, logged and drawn only).
  virtual bool rendersForce() const = 0;
  // The device's own limits, if it reports them; the session uses the tighter of these and its
  // settings.
  virtual std::optional<DeviceLimits> limits() const { return std::nullopt; }

  // Loop thread, once before the first tick / after the last (open the device, enable forces;
  // disable them). stop() must leave the device exerting no force.
  virtual void start() {}
  virtual void stop() noexcept {}
  // Loop thread, every tick: the tool tip (device frame, m) at loop time `t` (s). False when the
  // device has no fresh sample (not answering): the loop then commands zero force. Must not
  // block, allocate, or throw.
  virtual bool read(double t, Eigen::Vector3d& position) noexcept = 0;
  // Loop thread, every tick, after read(): the force to render (device frame, N).
  virtual void command(const Eigen::Vector3d& force) noexcept = 0;
};

// A device that follows a script: position = path(t), nullopt = not answering. For tests and
// benchmarks; remembers the last force it was commanded and how many.
class ScriptedDevice final : public HapticDevice {
 public:
  using Path = std::function<std::optional<Eigen::Vector3d>(double t)>;
  explicit ScriptedDevice(Path path, std::string name = "scripted")
      : path_(std::move(path)), name_(std::move(name)) {}

  // Piecewise-linear through (time, position) keyframes (times increasing); before the first /
  // after the last keyframe the end position is held.
  static Path keyframes(std::vector<std::pair<double, Eigen::Vector3d>> frames);

  std::string name() const override { return name_; }
  bool rendersForce() const override { return true; }
  bool read(double t, Eigen::Vector3d& position) noexcept override;
  void command(const Eigen::Vector3d& force) noexcept override;
  void stop() noexcept override { command(Eigen::Vector3d::Zero()); }

  // Read after the loop stopped (or from the loop's thread).
  Eigen::Vector3d lastForce() const { return last_; }
  std::uint64_t commands() const { return commands_.load(std::memory_order_relaxed); }

 private:
  Path path_;
  std::string name_;
  Eigen::Vector3d last_ = Eigen::Vector3d::Zero();
  std::atomic<std::uint64_t> commands_{0};
};

// The tracked tool marker as a position-only device: the tracker pushes the tip (device frame:
// the marker world, m) at camera rate from its own thread; the loop reads it at 1 kHz,
// interpolated between the two latest samples one camera frame late (so the path is continuous
// instead of a 30 Hz staircase). Older than `timeout` = not answering. Forces are not rendered:
// they are logged and drawn as an arrow.
class TrackedMarkerDevice final : public HapticDevice {
 public:
  explicit TrackedMarkerDevice(double timeout = 0.2);  // s, > 0

  // Tracker side (one thread): the tip at time t (on the loop's clock, increasing). A non-finite
  // position marks the marker as lost.
  void push(const Eigen::Vector3d& position, double t);

  std::string name() const override { return "tracked-marker"; }
  bool rendersForce() const override { return false; }
  bool read(double t, Eigen::Vector3d& position) noexcept override;
  void command(const Eigen::Vector3d&) noexcept override {}

 private:
  struct Pair {
    int count = 0;  // samples in (a, b): 0, 1 or 2
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
    double ta = 0, tb = 0;
  };
  double timeout_;
  Pair writer_;  // tracker thread's copy
  TripleBuffer<Pair> shared_;
};

}  // namespace ps::haptics
