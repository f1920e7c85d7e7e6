#include "edit/undo_journal.hpp"

#include <algorithm>
#include <bit>

#include "core/input_error.hpp"

namespace ps::edit {

void UndoJournal::beginStroke() {
  if (open_) throw core::InputError("undo journal: a stroke is already open");
  mergeOutside();
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

namespace {
bool sameBits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}
}  // namespace

void UndoJournal::recordOutside(std::span<const HeightChange> changes, const core::GridSize& grid,
                                const terrain::VertexBox& dirty, bool wrapsU) {
  if (changes.empty()) return;
  if (open_) {
    for (const HeightChange& c : changes)
      pending_.push_back({c.index | kOutside, c.before, c.after});
    pendingDirty_ = pendingDirty_.unite(dirty, grid, wrapsU);
    if (pending_.size() > 2 * compacted_ + (std::size_t(1) << 20)) compact();
    return;
  }
  // Between strokes the latest stroke takes them; after an undo that is the stroke below the
  // undone one, whose "before" heights stay right: a vertex it does not hold yet is at its
  // height from before it (the undo put it back). What can be redone stays redoable.
  if (done_.empty()) return;
  Stroke& s = done_.back();
  s.dirty = s.dirty.unite(dirty, grid, wrapsU);
  // Gathered, and merged once they outgrow the stroke (or before the journal next reads it), so
  // a long settle after a large stroke costs time in proportion to what it changes.
  bytes_ -= outside_.capacity() * sizeof(HeightChange);
  outside_.insert(outside_.end(), changes.begin(), changes.end());
  bytes_ += outside_.capacity() * sizeof(HeightChange);
  if (outside_.size() > s.changes.size() + (std::size_t(1) << 16)) mergeOutside();
  trim();
}

void UndoJournal::mergeOutside() {
  if (outside_.empty()) return;
  bytes_ -= outside_.capacity() * sizeof(HeightChange);
  // Time order within outside_ is kept by the stable sort, so a vertex changed twice keeps its
  // first "before" and its last "after"; a vertex the stroke holds keeps the stroke's "before".
  std::vector<HeightChange> changes = std::move(outside_);
  outside_.clear();
  std::stable_sort(changes.begin(), changes.end(),
                   [](const HeightChange& a, const HeightChange& b) { return a.index < b.index; });
  Stroke& s = done_.back();
  bytes_ -= s.bytes();
  std::vector<HeightChange> merged;
  merged.reserve(s.changes.size() + changes.size());
  std::size_t i = 0;
  for (std::size_t j = 0; j < changes.size();) {
    std::size_t k = j;
    while (k + 1 < changes.size() && changes[k + 1].index == changes[j].index) ++k;
    const std::uint32_t index = changes[j].index;
    while (i < s.changes.size() && s.changes[i].index < index) merged.push_back(s.changes[i++]);
    if (i < s.changes.size() && s.changes[i].index == index) {
      merged.push_back({index, s.changes[i++].before, changes[k].after});
    } else {
      merged.push_back({index, changes[j].before, changes[k].after});
    }
    j = k + 1;
  }
  merged.insert(merged.end(), s.changes.begin() + std::ptrdiff_t(i), s.changes.end());
  merged.shrink_to_fit();
  s.changes = std::move(merged);
  bytes_ += s.bytes();
}

void UndoJournal::compact() {
  // One entry per vertex: the first "before", the last "after" (stable sort keeps stamp order).
  // An entry whose height is back where it started is dropped (a later change records the same
  // "before" again), unless settling moved it in between (kOutside).
  auto vertex = [](const HeightChange& c) { return c.index & ~kOutside; };
  std::stable_sort(
      pending_.begin(), pending_.end(),
      [&](const HeightChange& a, const HeightChange& b) { return vertex(a) < vertex(b); });
  std::size_t out = 0;
  for (std::size_t i = 0; i < pending_.size();) {
    std::size_t j = i;
    std::uint32_t outside = pending_[i].index & kOutside;
    while (j + 1 < pending_.size() && vertex(pending_[j + 1]) == vertex(pending_[i])) {
      ++j;
      outside |= pending_[j].index & kOutside;
    }
    const HeightChange c{vertex(pending_[i]) | outside, pending_[i].before, pending_[j].after};
    if (outside || !sameBits(c.before, c.after)) pending_[out++] = c;
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
  for (HeightChange& c : s.changes) c.index &= ~kOutside;
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
  while (bytes_ > maxBytes_ && done_.size() > 1) {  // outside_ belongs to done_.back()
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
  mergeOutside();
  apply(terrain, done_.back(), false);
  undone_.push_back(std::move(done_.back()));
  done_.pop_back();
  if (listener_) listener_->onCommitted(JournalEvent::kUndo, undone_.back().changes);
}

void UndoJournal::redo(terrain::Terrain& terrain) {
  if (open_) throw core::InputError("cannot redo while a stroke is open");
  if (undone_.empty()) throw core::InputError("nothing to redo");
  mergeOutside();
  apply(terrain, undone_.back(), true);
  done_.push_back(std::move(undone_.back()));
  undone_.pop_back();
  if (listener_) listener_->onCommitted(JournalEvent::kRedo, done_.back().changes);
}

void UndoJournal::clear() {
  open_ = false;
  pending_.clear();
  outside_.clear();
  done_.clear();
  undone_.clear();
  bytes_ = 0;
}

}  // namespace ps::edit
