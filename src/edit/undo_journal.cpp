#include "edit/undo_journal.hpp"

#include <algorithm>
#include <bit>

#include "core/input_error.hpp"

namespace ps::edit {

void UndoJournal::beginStroke() {
  if (open_) throw core::InputError("undo journal: a stroke is already open");
  open_ = true;
  pending_.clear();
  compacted_ = 0;
  pendingDirty_ = terrain::VertexBox::none();
  for (const Stroke& s : undone_) bytes_ -= s.bytes();
  undone_.clear();
}

void UndoJournal::recordStamp(const Region& footprint, std::span<const float> before,
                              std::span<const float> heights, const core::GridSize& grid,
                              const terrain::VertexBox& dirty, bool wrapsU) {
  if (!open_) throw core::InputError("undo journal: recordStamp outside a stroke");
  std::size_t i = 0;
  footprint.forEachSpan([&](int v, int a, int b) {
    for (int u = a; u <= b; ++u, ++i) {
      const std::size_t k = grid.index(u, v);
      const float now = heights[k];
      if (std::bit_cast<std::uint32_t>(now) != std::bit_cast<std::uint32_t>(before[i])) {
        pending_.push_back({std::uint32_t(k), before[i], now});
      }
    }
  });
  pendingDirty_ = pendingDirty_.unite(dirty, grid, wrapsU);
  // Long strokes over the same vertices: keep memory proportional to what changed.
  if (pending_.size() > 2 * compacted_ + (std::size_t(1) << 20)) compact();
}

void UndoJournal::compact() {
  // One entry per vertex: the first "before", the last "after" (stable sort keeps stamp order).
  // An entry whose height is back where it started is dropped: a later change records the same
  // "before" again.
  std::stable_sort(pending_.begin(), pending_.end(),
                   [](const HeightChange& a, const HeightChange& b) { return a.index < b.index; });
  std::size_t out = 0;
  for (std::size_t i = 0; i < pending_.size();) {
    std::size_t j = i;
    while (j + 1 < pending_.size() && pending_[j + 1].index == pending_[i].index) ++j;
    const HeightChange c{pending_[i].index, pending_[i].before, pending_[j].after};
    if (std::bit_cast<std::uint32_t>(c.before) != std::bit_cast<std::uint32_t>(c.after))
      pending_[out++] = c;
    i = j + 1;
  }
  pending_.resize(out);
  compacted_ = out;
}

std::size_t UndoJournal::endStroke(const core::GridSize& grid) {
  if (!open_) throw core::InputError("undo journal: endStroke without a stroke");
  open_ = false;
  compact();
  Stroke s;
  s.gridCount = grid.count();
  s.dirty = pendingDirty_;
  s.changes.assign(pending_.begin(), pending_.end());
  pending_.clear();
  pending_.shrink_to_fit();
  compacted_ = 0;
  const std::size_t n = s.changes.size();
  s.changes.shrink_to_fit();
  bytes_ += s.bytes();
  done_.push_back(std::move(s));
  if (listener_) listener_->onCommitted(JournalEvent::kStroke, done_.back().changes);
  trim();
  return n;
}

void UndoJournal::setMaxBytes(std::size_t maxBytes) {
  maxBytes_ = maxBytes;
  trim();
}

void UndoJournal::trim() {
  while (bytes_ > maxBytes_ && done_.size() > 1) {
    bytes_ -= done_.front().bytes();
    done_.pop_front();
  }
}

void UndoJournal::apply(terrain::Terrain& terrain, const Stroke& s, bool forward) {
  if (terrain.grid().count() != s.gridCount) {
    throw core::InputError("undo journal: the terrain is not the " + std::to_string(s.gridCount) +
                           "-vertex grid the strokes were recorded on");
  }
  auto h = terrain.mutableHeights();
  for (const HeightChange& c : s.changes) h[c.index] = forward ? c.after : c.before;
  terrain.commitEdit(s.dirty);
}

void UndoJournal::undo(terrain::Terrain& terrain) {
  if (open_) throw core::InputError("cannot undo while a stroke is open");
  if (done_.empty()) throw core::InputError("nothing to undo");
  apply(terrain, done_.back(), false);
  undone_.push_back(std::move(done_.back()));
  done_.pop_back();
  if (listener_) listener_->onCommitted(JournalEvent::kUndo, undone_.back().changes);
}

void UndoJournal::redo(terrain::Terrain& terrain) {
  if (open_) throw core::InputError("cannot redo while a stroke is open");
  if (undone_.empty()) throw core::InputError("nothing to redo");
  apply(terrain, undone_.back(), true);
  done_.push_back(std::move(undone_.back()));
  undone_.pop_back();
  if (listener_) listener_->onCommitted(JournalEvent::kRedo, done_.back().changes);
}

void UndoJournal::clear() {
  open_ = false;
  pending_.clear();
  done_.clear();
  undone_.clear();
  bytes_ = 0;
}

}  // namespace ps::edit
