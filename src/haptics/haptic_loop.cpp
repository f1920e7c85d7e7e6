#include "haptics/haptic_loop.hpp"

#include <pthread.h>
#include <sched.h>

#include <cmath>

#include "core/input_error.hpp"
#include "haptics/spsc_queue.hpp"

namespace ps::haptics {

using Clock = std::chrono::steady_clock;

void LoopOptions::validate(double period) const {
  if (!(std::isfinite(spinSeconds) && spinSeconds >= 0 && spinSeconds < period))
    throw core::InputError("haptics: spin = " + std::to_string(spinSeconds) +
                           " s must be in [0, period)");
  if (recordCapacity < 2 || recordCapacity > (std::size_t(1) << 24))
    throw core::InputError("haptics: record capacity = " + std::to_string(recordCapacity) +
                           " must be in [2, 2^24]");
  if (timingCapacity > (std::size_t(1) << 26))
    throw core::InputError("haptics: timing capacity = " + std::to_string(timingCapacity) +
                           " must be at most 2^26");
}

namespace {
const HapticSettings& checked(const HapticSettings& s, const LoopOptions& o) {
  s.validate();
  o.validate(s.period());
  return s;
}
}  // namespace

HapticLoop::HapticLoop(HapticDevice& device, const HapticSettings& settings,
                       const WorkspaceMap& map, LoopOptions options)
    : device_(device),
      core_(checked(settings, options), map),
      options_(options),
      epoch_(Clock::now()),
      records_(std::make_unique<SpscQueue<ForceRecord>>(options.recordCapacity)),
      timings_(options.timingCapacity) {}

HapticLoop::~HapticLoop() {
  stop();
}

std::size_t HapticLoop::drain(std::vector<ForceRecord>& out) {
  return records_->drain(out);
}

double HapticLoop::now() const {
  if (options_.tickClock) return tickSeconds(ticks_.load(std::memory_order_acquire));
  return std::chrono::duration<double>(Clock::now() - epoch_).count();
}

void HapticLoop::start() {
  if (running()) return;
  core_.reset();
  thread_ = std::jthread([this](std::stop_token st) { run(st); });
}

void HapticLoop::stop() {
  if (!running()) return;
  thread_.request_stop();
  thread_.join();
  thread_ = std::jthread();
}

void HapticLoop::publishPatch(const terrain::Terrain& terrain, const Eigen::Vector3d& centre,
                              int halfSize, const terrain::MeshPatch* surface) {
  TerrainPatch& p = patches_.back();
  if (!p.capture(terrain, centre, halfSize, surface)) p.clear();
  patches_.publish();
}

std::optional<ForceRecord> HapticLoop::latest() {
  if (ticks_.load(std::memory_order_acquire) == 0) return std::nullopt;
  latest_.update();
  return latest_.front();
}

void HapticLoop::waitForTicks(std::uint64_t ticks) const {
  for (std::uint64_t seen = ticks_.load(std::memory_order_acquire); seen < ticks;
       seen = ticks_.load(std::memory_order_acquire)) {
    ticks_.wait(seen, std::memory_order_acquire);
  }
}

LoopStats HapticLoop::stats() const {
  LoopStats s;
  s.ticks = ticks_.load(std::memory_order_relaxed);
  s.missedDeadlines = missed_.load(std::memory_order_relaxed);
  s.droppedRecords = records_->dropped();
  for (std::size_t i = 0; i < s.faults.size(); ++i)
    s.faults[i] = faults_[i].load(std::memory_order_relaxed);
  s.maxComputeUs = maxComputeUs_.load(std::memory_order_relaxed);
  s.realtimePriority = rt_.load(std::memory_order_relaxed);
  s.running = running();
  return s;
}

std::vector<TickTiming> HapticLoop::timings() const {
  const std::size_t n = std::min(timingCount_.load(std::memory_order_acquire), timings_.size());
  return {timings_.begin(), timings_.begin() + std::ptrdiff_t(n)};
}

void HapticLoop::run(std::stop_token stop) {
  if (options_.realtimePriority) {
    sched_param sp{};
    sp.sched_priority = std::max(1, sched_get_priority_max(SCHED_FIFO) - 10);
    rt_.store(pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0);
  }
  device_.start();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(core_.model().settings().period()));
  const auto spin = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options_.spinSeconds));
  auto next = Clock::now() + period;
  auto lastWake = Clock::time_point{};
  while (!stop.stop_requested()) {
    std::this_thread::sleep_until(next - spin);
    while (Clock::now() < next) {
    }
    const auto wake = Clock::now();
    patches_.update();
    const TerrainPatch& patch = patches_.front();
    const double t = options_.tickClock ? tickSeconds(ticks_.load(std::memory_order_relaxed) + 1)
                                        : std::chrono::duration<double>(wake - epoch_).count();
    Eigen::Vector3d pos = Eigen::Vector3d::Zero();
    const bool ok = device_.read(t, pos);
    const ForceRecord r = core_.tick(t, ok, pos, patch.valid() ? &patch : nullptr);
    device_.command(r.force);
    records_->push(r);
    latest_.back() = r;
    latest_.publish();
    if (r.fault != Fault::kNone)
      faults_[std::size_t(r.fault)].fetch_add(1, std::memory_order_relaxed);
    const auto done = Clock::now();
    const double computeUs = std::chrono::duration<double, std::micro>(done - wake).count();
    if (computeUs > maxComputeUs_.load(std::memory_order_relaxed))
      maxComputeUs_.store(computeUs, std::memory_order_relaxed);
    const std::size_t k = timingCount_.load(std::memory_order_relaxed);
    if (k < timings_.size() && lastWake != Clock::time_point{}) {
      timings_[k].periodUs =
          float(std::chrono::duration<double, std::micro>(wake - lastWake).count());
      timings_[k].computeUs = float(computeUs);
      timingCount_.store(k + 1, std::memory_order_release);
    }
    lastWake = wake;
    ticks_.fetch_add(1, std::memory_order_release);
    ticks_.notify_all();  // no system call unless a thread waits in waitForTicks
    next += period;
    if (done > next + period) {  // more than a period behind: skip, keep the phase
      const auto behind = (done - next) / period;
      missed_.fetch_add(std::uint64_t(behind), std::memory_order_relaxed);
      next += behind * period;
    }
  }
  device_.command(Eigen::Vector3d::Zero());
  device_.stop();
}

}  // namespace ps::haptics
