#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "edit/region_growing.hpp"
#include "terrain/terrain.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::edit {

// One vertex a stroke changed: its height before the stroke and after it.
struct HeightChange {
  std::uint32_t index = 0;  // v * side + u (32769^2 < 2^32)
  float before = 0, after = 0;
};

// What made a change to the heights final, as a JournalListener hears it.
enum class JournalEvent {
  kStroke,  // a stroke ended: its vertices now hold their "after" heights
  kUndo,    // a stroke was undone: its vertices hold their "before" heights again
  kRedo,    // a stroke was redone: "after" again
};

// Told about every stroke, undo and redo once its heights are written (the live app's on-disk
// stroke journal, session/session_store.hpp). `changes` holds the stroke's vertices, sorted by
// index; the heights the terrain now holds are `after` for kStroke and kRedo, `before` for
// kUndo, unless something outside the journal (sand settling between a stroke's stamps) moved
// them since. Must not throw (the journal's state has already changed).
class JournalListener {
 public:
  virtual ~JournalListener() = default;
  virtual void onCommitted(JournalEvent event, std::span<const HeightChange> changes) noexcept = 0;
};

// Undo and redo of whole strokes. A stroke stores only the vertices whose height it changed
// (bitwise; with the settling that followed it, recordOutside), each once with its height before
// the stroke's first stamp and after its last:
// 12 bytes per changed vertex, plus the stroke's dirty rectangle. Undo writes the "before"
// heights back and commits the dirty rectangle, so the error bounds are recomputed over it and -
// being bit-for-bit a function of the heights - come back bit for bit too. (Terrain's
// minHeight/maxHeight only ever widen and are not restored.)
//
// When the strokes held exceed maxBytes the oldest are forgotten (no longer undoable).
class UndoJournal {
 public:
  explicit UndoJournal(std::size_t maxBytes = std::size_t(256) << 20) : maxBytes_(maxBytes) {}

  // Strokes. A new stroke drops everything that could be redone.
  void beginStroke();
  bool inStroke() const { return open_; }
  // During a stroke, after a stamp: `before` holds the heights of `footprint` in its span order
  // as they were before the stamp, `heights` the current ones; changed vertices are recorded.
  void recordStamp(const Region& footprint, std::span<const float> before,
                   std::span<const float> heights, const core::GridSize& grid,
                   const terrain::VertexBox& dirty, bool wrapsU);
  // Heights changed outside the journal's strokes, by something that follows from them (sand
  // settling): `changes` (any order, each with its height before this change and after it) join
  // the open stroke, or when none is open the latest stroke, so that undoing a stroke also takes
  // back the settling that followed it, and the planet returns to its state at the stroke's
  // beginning. When there is nothing to undo the changes are not recorded (the heights the
  // journal began with). What can be redone stays redoable (a redo writes its stroke's "after"
  // heights over what settled since the undo).
  void recordOutside(std::span<const HeightChange> changes, const core::GridSize& grid,
                     const terrain::VertexBox& dirty, bool wrapsU);
  // Closes the stroke and returns its changed-vertex count. A stroke that changed nothing is still
  // one undo step (so "undo" always takes back the user's last stroke).
  std::size_t endStroke(const core::GridSize& grid);

  std::size_t undoCount() const { return done_.size(); }
  std::size_t redoCount() const { return undone_.size(); }
  // Throws core::InputError when there is nothing to undo/redo, a stroke is open, or `terrain`
  // is not the grid the journal recorded.
  void undo(terrain::Terrain& terrain);
  void redo(terrain::Terrain& terrain);
  void clear();

  // One listener (or none); it must outlive the journal or be reset first.
  void setListener(JournalListener* listener) { listener_ = listener; }
  JournalListener* listener() const { return listener_; }

  std::size_t bytes() const { return bytes_; }
  std::size_t maxBytes() const { return maxBytes_; }
  // Lowering the cap forgets the oldest strokes until the journal fits (always keeping one).
  void setMaxBytes(std::size_t maxBytes);
  // Changed vertices of the most recent undoable stroke (0 when none); settling recorded since it
  // ended may not be counted yet.
  std::size_t lastStrokeChanges() const { return done_.empty() ? 0 : done_.back().changes.size(); }

 private:
  struct Stroke {
    std::vector<HeightChange> changes;  // sorted by index, unique
    terrain::VertexBox dirty;
    std::size_t gridCount = 0;
    std::size_t bytes() const { return changes.capacity() * sizeof(HeightChange) + sizeof(Stroke); }
  };
  void apply(terrain::Terrain& terrain, const Stroke& s, bool forward);
  void trim();
  void compact();       // pending_: one entry per vertex, no-op entries dropped (but see kOutside)
  void mergeOutside();  // outside_ into done_.back()

  // pending_'s entries from recordOutside carry this bit in `index` (grids hold < 2^31 vertices)
  // until the stroke ends: a vertex that settling moved and a stamp put back where it began is
  // kept (a no-op for undo), so the stroke's record (JournalListener) writes its height.
  static constexpr std::uint32_t kOutside = 0x80000000u;

  std::size_t maxBytes_;
  std::size_t bytes_ = 0;
  bool open_ = false;
  std::vector<HeightChange> pending_;
  std::size_t compacted_ = 0;  // pending_.size() after the last compact()
  terrain::VertexBox pendingDirty_;
  std::vector<HeightChange> outside_;  // recordOutside's since the latest stroke, not merged yet
  std::deque<Stroke> done_;
  std::vector<Stroke> undone_;
  JournalListener* listener_ = nullptr;
};

}  // namespace ps::edit
