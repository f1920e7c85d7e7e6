#include "render/changed_ranges.hpp"

#include <algorithm>
#include <cstring>

namespace ps::render {

std::vector<ByteRange> changedRanges(std::span<const std::uint8_t> previous,
                                     std::span<const std::uint8_t> next, std::size_t chunk) {
  std::vector<ByteRange> out;
  if (chunk == 0) chunk = 1;
  for (std::size_t at = 0; at < next.size(); at += chunk) {
    const std::size_t n = std::min(chunk, next.size() - at);
    const bool same =
        at + n <= previous.size() && std::memcmp(previous.data() + at, next.data() + at, n) == 0;
    if (same) continue;
    if (!out.empty() && out.back().offset + out.back().size == at) {
      out.back().size += n;
    } else {
      out.push_back({at, n});
    }
  }
  return out;
}

}  // namespace ps::render
