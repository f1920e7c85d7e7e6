#pragma once
// The fixed-rate haptic thread. Every period (1 ms at the default 1 kHz) it
//   1. takes the newest terrain snapshot if the editor published one (wait-free triple buffer),
//   2. reads the tool tip from the device,
//   3. computes the force (HapticCore: depth in the snapshot, force law, clamps, ramp),
//   4. commands it and queues a ForceRecord (wait-free ring; full = dropped and counted).
// It never takes a lock the editor holds, never allocates, never edits the terrain. The editor
// thread publishes snapshots (publishPatch), drains the records (for the log, the AR arrow and
// the presses that drive the sand displacement through the edit pipeline) and reads stats.
// Timing: sleep_until the next deadline minus a short spin, then spin to it; a tick that ends
// past the next deadline skips the missed ones (no catch-up burst) and counts them.
#include <Eigen/Core>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptics/device.hpp"
#include "haptics/haptic_core.hpp"
#include "haptics/terrain_patch.hpp"
#include "haptics/triple_buffer.hpp"

namespace ps::haptics {

template <class T>
class SpscQueue;

struct LoopOptions {
  double spinSeconds = 200e-6;        // busy-wait before each deadline, [0, period)
  bool realtimePriority = true;       // try SCHED_FIFO (needs CAP_SYS_NICE; failure is reported)
  std::size_t recordCapacity = 8192;  // ticks the editor may fall behind before records drop
  std::size_t timingCapacity = 0;     // ticks whose period and compute time are kept (bench)
  // The time the device and the force model see: the wall clock since construction (false), or
  // ticks x period (true), so that a loaded machine delays ticks but never skips any of a
  // scripted device's time: what the loop computes then depends on the tick count alone
  // (tests of the live thread).
  bool tickClock = false;
  void validate(double period) const;
};

struct TickTiming {
  float periodUs = 0;   // wake-up to previous wake-up
  float computeUs = 0;  // read + force + command + queue
};

struct LoopStats {
  std::uint64_t ticks = 0;
  std::uint64_t missedDeadlines = 0;  // periods skipped after an overrun
  std::uint64_t droppedRecords = 0;
  std::array<std::uint64_t, 6> faults{};  // by Fault
  double maxComputeUs = 0;
  bool realtimePriority = false;  // SCHED_FIFO obtained
  bool running = false;
};

class HapticLoop {
 public:
  // The device must outlive the loop. Validates settings, map and options.
  HapticLoop(HapticDevice& device, const HapticSettings& settings, const WorkspaceMap& map,
             LoopOptions options = {});
  ~HapticLoop();
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  void start();
  void stop();  // joins; the device is left commanding zero force
  bool running() const { return thread_.joinable(); }
  // Seconds on the loop's clock (0 at construction; LoopOptions::tickClock: the last tick's
  // time); devices are read with this time.
  double now() const;

  // Editor thread (one thread): snapshot of the heights within halfSize cells of `centre`
  // (planet frame) for the loop to read.
  void publishPatch(const terrain::Terrain& terrain, const Eigen::Vector3d& centre, int halfSize,
                    const terrain::MeshPatch* surface = nullptr);
  // Editor thread: everything queued since the last drain, oldest first.
  std::size_t drain(std::vector<ForceRecord>& out);
  // Editor thread: the newest tick (tip and force), if any ran.
  std::optional<ForceRecord> latest();

  LoopStats stats() const;
  // Another thread: blocks (no spinning) until the loop has run `ticks` ticks. The loop must be
  // running, or keep running until then.
  void waitForTicks(std::uint64_t ticks) const;
  // After stop(): the kept tick timings (LoopOptions::timingCapacity).
  std::vector<TickTiming> timings() const;

  const WorkspaceMap& map() const { return core_.map(); }
  const HapticSettings& settings() const { return core_.model().settings(); }

 private:
  void run(std::stop_token stop);
  // LoopOptions::tickClock's time of tick number `ticks` (counted from 1).
  double tickSeconds(std::uint64_t ticks) const {
    return double(ticks) * core_.model().settings().period();
  }

  HapticDevice& device_;
  HapticCore core_;
  LoopOptions options_;
  std::chrono::steady_clock::time_point epoch_;
  TripleBuffer<TerrainPatch> patches_;
  TripleBuffer<ForceRecord> latest_;
  std::unique_ptr<SpscQueue<ForceRecord>>
      records_;  // haptics/spsc_queue.hpp (Boost), kept out of this header
  std::vector<TickTiming> timings_;
  std::atomic<std::size_t> timingCount_{0};
  std::atomic<std::uint64_t> ticks_{0}, missed_{0};
  std::array<std::atomic<std::uint64_t>, 6> faults_{};
  std::atomic<double> maxComputeUs_{0};
  std::atomic<bool> rt_{false};
  std::jthread thread_;
};

}  // namespace ps::haptics
