#pragma once
#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <vector>

#include "core/chart.hpp"
#include "core/huge_page_allocator.hpp"
#include "terrain/error_bounds.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::terrain {

// The planet: a chart, one height per grid vertex (metres, along the chart's up direction) and
// the nested error bounds the tessellator and exporters read. Heights are float: on a 6,372 km
// planet with relief within +-100 km a float height resolves better than 8 mm.
class Terrain {
 public:
  // Heights must be finite, within +-heightLimit(), equal on seam twins and along each pole
  // row; otherwise core::InputError names the first offending vertex.
  Terrain(std::shared_ptr<const core::Chart> chart, std::vector<float> heights,
          ErrorRule rule = ErrorRule::kHybridExact,
          BoundsContent content = BoundsContent::kErrorsAndRadii);

  const core::Chart& chart() const { return *chart_; }
  std::shared_ptr<const core::Chart> chartPtr() const { return chart_; }
  const core::GridSize& grid() const { return chart_->grid(); }
  std::span<const float> heights() const { return heights_; }
  float height(int u, int v) const { return heights_[grid().index(u, v)]; }
  const ErrorBounds& bounds() const { return bounds_; }

  // Saturation limit for heights (edits clamp to it).
  double heightLimit() const { return chart_->heightLimit(); }

  // Editing: change heights through mutableHeights(), then report what changed with
  // commitEdit(); the bounds are updated above that region only and the revision advances.
  // Editors keep seam twins and pole rows consistent (see edit::applyToVertex).
  std::span<float> mutableHeights() { return heights_; }
  void commitEdit(const VertexBox& changed);
  // The same for an edit whose changed heights all lie in `changed`, images across glued sides
  // already among them (gluedImages), each cut to its part of the edit (edit::EditPipeline).
  void commitEdit(std::span<const CutBox> changed);
  void rebuildBounds(ErrorRule rule, BoundsContent content = BoundsContent::kErrorsAndRadii);

  // Unique across all terrains of the process and renewed whenever heights or bounds change:
  // a tessellation cached for one revision is valid as long as the revision is the same.
  std::uint64_t revision() const { return revision_; }

  // The regions whose heights changed after `revision` (a revision of this terrain), for
  // copies that follow the heights (a GPU texture sends only what changed). False when that
  // revision is older than the changes kept (the last kKeptChanges) or not this terrain's:
  // then anything may have changed.
  static constexpr std::size_t kKeptChanges = 256;
  bool changedSince(std::uint64_t revision, std::vector<VertexBox>& regions) const;

  // Lowest and highest height, refreshed on commitEdit (used by horizon culling).
  float minHeight() const { return minHeight_; }
  float maxHeight() const { return maxHeight_; }

  std::size_t bytes() const { return heights_.size() * sizeof(float) + bounds_.bytes(); }

  // Throws InputError naming the first vertex that breaks a rule Terrain enforces.
  static void validateHeights(const core::Chart& chart, std::span<const float> heights);

 private:
  void refreshHeightRange();

  std::shared_ptr<const core::Chart> chart_;
  std::vector<float, core::HugePageAllocator<float>> heights_;
  ErrorBounds bounds_;
  std::uint64_t revision_ = 0;
  // Each committed change with the revision it made; oldestKnown_ is the revision from which
  // this list is complete.
  struct Change {
    std::uint64_t revision;
    VertexBox region;
  };
  std::deque<Change> changes_;
  std::uint64_t oldestKnown_ = 0;
  void recordChange(const VertexBox& region);
  float minHeight_ = 0, maxHeight_ = 0;
};

}  // namespace ps::terrain
