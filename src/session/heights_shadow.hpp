#pragma once
// A second copy of the planet's heights that a writer thread saves from while the frame loop
// goes on sculpting the first (session/session_writer.hpp). Copying 8193² heights (256 MiB)
// at a save would stall a frame, so the copy follows the terrain instead: each frame notes the
// regions the terrain's edits changed since the last look (Terrain::changedSince) and copies
// those rows' changed spans, a bounded number of bytes per frame. When nothing noted is left
// the copy equals the terrain bit for bit.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "terrain/terrain.hpp"

namespace ps::session {

class HeightsShadow {
 public:
  explicit HeightsShadow(const terrain::Terrain& planet);  // a full copy

  // Notes what changed since the last call (every row when the terrain no longer keeps that
  // far back). Cheap: call it after every edit or once a frame.
  void follow(const terrain::Terrain& planet);
  // Copies noted spans, row by row, until about `maxBytes` are copied (SIZE_MAX: all of them);
  // returns the bytes copied. Only while no one reads heights().
  std::size_t catchUp(const terrain::Terrain& planet, std::size_t maxBytes);
  // True when the copy equals the terrain as of the last follow().
  bool current() const { return dirtyRows_ == 0; }
  std::size_t pendingRows() const { return dirtyRows_; }

  std::span<const float> heights() const { return heights_; }

 private:
  void noteAll();
  void note(const terrain::VertexBox& region);

  core::GridSize grid_;
  int side_ = 0;
  std::vector<float> heights_;
  // Per row the changed span [first, last] (first > last: nothing), and the rows that have one.
  std::vector<int> first_, last_;
  std::size_t dirtyRows_ = 0;
  int lowRow_ = 0, highRow_ = -1;  // the noted rows lie within [lowRow_, highRow_]
  std::uint64_t revision_ = 0;
  std::vector<terrain::VertexBox> scratch_;
};

}  // namespace ps::session
