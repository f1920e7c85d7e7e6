#include "session/heights_shadow.hpp"

#include <algorithm>
#include <cstring>

namespace ps::session {

HeightsShadow::HeightsShadow(const terrain::Terrain& planet)
    : grid_(planet.grid()),
      side_(planet.grid().side()),
      heights_(planet.heights().begin(), planet.heights().end()),
      first_(std::size_t(side_), side_),
      last_(std::size_t(side_), -1),
      revision_(planet.revision()) {}

void HeightsShadow::noteAll() {
  for (int v = 0; v < side_; ++v) note(terrain::VertexBox{0, side_ - 1, v, v});
}

void HeightsShadow::note(const terrain::VertexBox& region) {
  if (region.empty()) return;
  region.forEachColumnRange(grid_, [&](int u0, int u1) {
    for (int v = std::max(0, region.vBegin); v <= std::min(side_ - 1, region.vEnd); ++v) {
      const std::size_t r = std::size_t(v);
      if (first_[r] > last_[r]) {
        ++dirtyRows_;
        if (dirtyRows_ == 1) lowRow_ = highRow_ = v;
        lowRow_ = std::min(lowRow_, v), highRow_ = std::max(highRow_, v);
      }
      first_[r] = std::min(first_[r], u0);
      last_[r] = std::max(last_[r], u1);
    }
  });
}

void HeightsShadow::follow(const terrain::Terrain& planet) {
  if (planet.revision() == revision_) return;
  if (planet.changedSince(revision_, scratch_)) {
    for (const terrain::VertexBox& r : scratch_) note(r);
  } else {
    noteAll();
  }
  revision_ = planet.revision();
}

std::size_t HeightsShadow::catchUp(const terrain::Terrain& planet, std::size_t maxBytes) {
  std::size_t copied = 0;
  const auto h = planet.heights();
  while (dirtyRows_ > 0 && copied < maxBytes) {
    const std::size_t r = std::size_t(lowRow_++);
    if (first_[r] > last_[r]) continue;
    const std::size_t at = r * std::size_t(side_) + std::size_t(first_[r]);
    const std::size_t n = std::size_t(last_[r] - first_[r] + 1);
    std::memcpy(heights_.data() + at, h.data() + at, n * sizeof(float));
    copied += n * sizeof(float);
    first_[r] = side_, last_[r] = -1;
    --dirtyRows_;
  }
  return copied;
}

}  // namespace ps::session
