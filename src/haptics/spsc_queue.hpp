#pragma once
// Bounded wait-free single-producer / single-consumer ring: the haptic thread pushes (never
// blocks; a full ring drops the item and counts it), the editor thread drains. The ring is
// Boost's (boost::lockfree::spsc_queue, header-only, installed with CGAL); this adds the count
// of dropped items and a drain into a vector. Its headers add about 57,000 preprocessed lines
// (98k against 41k for a file that includes only this), so only haptic_loop.cpp and the test
// include this file: HapticLoop holds the queue through a pointer.
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ps::haptics {

template <class T>
class SpscQueue {
 public:
  // Holds up to `capacity` items (>= 1).
  explicit SpscQueue(std::size_t capacity)
      : ring_(capacity < 1 ? 1 : capacity), capacity_(capacity < 1 ? 1 : capacity) {}
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  // Producer. False (and the item dropped) when full.
  bool push(const T& item) {
    if (ring_.push(item)) return true;
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  // Consumer: appends everything queued to `out`, oldest first; returns how many.
  std::size_t drain(std::vector<T>& out) {
    return ring_.consume_all([&out](const T& item) { out.push_back(item); });
  }

  std::size_t capacity() const { return capacity_; }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  boost::lockfree::spsc_queue<T> ring_;
  std::size_t capacity_;
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace ps::haptics
