#pragma once
// Bounded wait-free single-producer / single-consumer ring: the haptic thread pushes (never
// blocks; a full ring drops the item and counts it), the editor thread drains.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ps::haptics {

template <class T>
class SpscQueue {
 public:
  // capacity is rounded up to a power of two (>= 2).
  explicit SpscQueue(std::size_t capacity) {
    std::size_t c = 2;
    while (c < capacity) c *= 2;
    buf_.resize(c);
    mask_ = c - 1;
  }
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  // Producer. False (and the item dropped) when full.
  bool push(const T& item) {
    const std::size_t h = head_.load(std::memory_order_relaxed);
    if (h - tail_.load(std::memory_order_acquire) > mask_) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    buf_[h & mask_] = item;
    head_.store(h + 1, std::memory_order_release);
    return true;
  }

  // Consumer: appends everything queued to `out`; returns how many.
  std::size_t drain(std::vector<T>& out) {
    const std::size_t t = tail_.load(std::memory_order_relaxed);
    const std::size_t h = head_.load(std::memory_order_acquire);
    for (std::size_t i = t; i != h; ++i) out.push_back(buf_[i & mask_]);
    tail_.store(h, std::memory_order_release);
    return h - t;
  }

  std::size_t capacity() const { return mask_ + 1; }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::vector<T> buf_;
  std::size_t mask_ = 1;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace ps::haptics
