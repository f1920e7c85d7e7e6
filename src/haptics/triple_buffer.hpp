#pragma once
// Wait-free single-producer / single-consumer hand-over of the latest value (a triple buffer).
// The writer fills its own slot and swaps it with the middle one; the reader swaps the middle
// into its own slot when a fresh value is there. Neither side ever waits for the other, and the
// reader never allocates or frees (the writer may resize the value in its own slot).
#include <array>
#include <atomic>
#include <cstdint>

namespace ps::haptics {

template <class T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // Writer side (one thread): fill back(), then publish().
  T& back() { return slots_[back_]; }
  void publish() {
    back_ = middle_.exchange(std::uint8_t(back_ | kFresh), std::memory_order_acq_rel) & kIndex;
  }

  // Reader side (one thread): take the newest published value if there is one; front() stays
  // valid (and unchanged) until the next update(). Returns true when front() changed.
  bool update() {
    if (!(middle_.load(std::memory_order_relaxed) & kFresh)) return false;
    front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    return true;
  }
  const T& front() const { return slots_[front_]; }
  T& front() { return slots_[front_]; }

  static_assert(std::atomic<std::uint8_t>::is_always_lock_free);

 private:
  static constexpr std::uint8_t kIndex = 3, kFresh = 4;
  std::array<T, 3> slots_{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // writer's
  std::uint8_t front_ = 2;  // reader's
};

}  // namespace ps::haptics
