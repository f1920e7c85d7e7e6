#pragma once
// Which parts of a GPU buffer must be sent again: the new contents are compared with a copy of
// what the buffer holds, chunk by chunk, and only runs of changed chunks are uploaded. A mesh
// re-tessellated after an edit under a held view keeps most of its bytes (the triangles before
// the edit in the bintree's order, and every vertex whose position did not move), so most
// chunks stay where they are.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ps::render {

struct ByteRange {
  std::size_t offset = 0, size = 0;
  bool operator==(const ByteRange&) const = default;
};

// Byte ranges of `next` that differ from `previous` (compared in chunks of `chunk` bytes;
// adjacent changed chunks merge into one range). Bytes of `next` beyond the end of `previous`
// count as changed. Ranges cover [0, next.size()) only.
std::vector<ByteRange> changedRanges(std::span<const std::uint8_t> previous,
                                     std::span<const std::uint8_t> next, std::size_t chunk);

// A GPU buffer with a CPU copy of its contents (the copy is what changedRanges compares with).
// The GL calls go through the two callbacks so this class holds no GL state of its own.
class ShadowedBuffer {
 public:
  static constexpr std::size_t kChunk = 4 * 1024;

  // Replaces the buffer's contents with `bytes`: when they fit the allocation, only changed
  // ranges are written (subData(offset, size, data)); otherwise, or with `everything`, the
  // buffer is reallocated with room to grow (allocate(capacity, data, size)) and everything is
  // sent. Returns bytes sent.
  template <class Allocate, class SubData>
  std::size_t update(std::span<const std::uint8_t> bytes, bool everything, Allocate&& allocate,
                     SubData&& subData) {
    std::size_t sent = 0;
    if (everything || bytes.size() > capacity_ || capacity_ == 0) {
      capacity_ = std::max<std::size_t>(kChunk, bytes.size() + bytes.size() / 4);
      allocate(capacity_, bytes.data(), bytes.size());
      sent = bytes.size();
    } else {
      for (const ByteRange& r : changedRanges(shadow_, bytes, kChunk)) {
        subData(r.offset, r.size, bytes.data() + r.offset);
        sent += r.size;
      }
    }
    shadow_.assign(bytes.begin(), bytes.end());
    return sent;
  }
  std::size_t size() const { return shadow_.size(); }

 private:
  std::vector<std::uint8_t> shadow_;
  std::size_t capacity_ = 0;
};

}  // namespace ps::render
