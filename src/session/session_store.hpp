#pragma once
// The live session's planet on disk (docs/LIVE.md): OUT/planet.planet, saved atomically at
// start, every `autosaveSeconds` and at the end, and OUT/planet.journal, the strokes since that
// save (io/stroke_journal.hpp), one record appended and flushed per finished stroke, undo and
// redo (heard from the edit pipeline's undo journal) and per frame of sand settling. After a
// save the journal starts again, its header naming the saved heights' checksum, so a journal is
// never applied to another planet. A crash loses at most the stroke in progress (and records
// still queued: a few milliseconds' worth). The disk work runs on a writer thread
// (session/session_writer.hpp), the planet saved from a HeightsShadow that follows the terrain.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "edit/undo_journal.hpp"
#include "io/stroke_journal.hpp"
#include "session/heights_shadow.hpp"
#include "session/session_writer.hpp"
#include "terrain/terrain.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::session {

struct SessionFiles {
  std::filesystem::path planet, journal;
  static SessionFiles in(const std::filesystem::path& outDir) {
    return {outDir / "planet.planet", outDir / "planet.journal"};
  }
};

// What a journal left by an earlier session holds, found before a new session starts
// (Recovery::inspect touches nothing).
class Recovery {
 public:
  enum class State {
    kNone,          // no journal, or one with no record: nothing to recover
    kRecoverable,   // strokes newer than the planet file, for its very heights
    kAlreadySaved,  // the planet file already holds everything the journal says
    kRefused,       // another planet's journal, an unreadable one, or no planet file for it
  };

  static Recovery inspect(const SessionFiles& files);

  State state() const { return state_; }
  const SessionFiles& files() const { return files_; }
  // The records recover() applies (a save mark's point on, marks not counted).
  std::size_t records() const { return journal_ ? io::heightRecordsFrom(*journal_, first_) : 0; }
  // One or two lines for the user, naming the files (and what a torn last record lost).
  const std::string& message() const { return message_; }

  // kRecoverable only: the planet file with the journal's records applied.
  std::unique_ptr<terrain::Terrain> recover() const;
  // Moves the journal out of the way, to `journal` + ".discarded" (kRecoverable: the user said
  // so) or ".refused" (kRefused), so the new session's journal does not overwrite it; returns
  // where it went ("" when there was nothing to move).
  std::filesystem::path setAside() const;

 private:
  SessionFiles files_;
  State state_ = State::kNone;
  std::optional<io::JournalContents> journal_;
  std::size_t first_ = 0;      // the first record that applies to the planet file
  std::uint32_t baseCrc_ = 0;  // the heights' checksum it applies to
  std::string message_;
};

struct SessionStoreOptions {
  double autosaveSeconds = 60;  // <= 0: no autosave (saves at start, on request and at the end)
  bool syncRecords = true;      // fdatasync every stroke, undo and redo record
  // Heights the frame loop copies into the save's shadow per tick (HeightsShadow::catchUp):
  // about a millisecond; a stroke across the seam dirties whole rows (8193²: 32 KiB each).
  std::size_t copyBytesPerTick = std::size_t(2) << 20;
  SessionWriterOptions writer{};
};

class SessionStore final : public edit::JournalListener {
 public:
  // Saves `planet` to files.planet and starts files.journal for it (waits for both). `now` (s,
  // any clock) starts the autosave clock. Throws std::runtime_error naming the file when the
  // disk refuses.
  SessionStore(terrain::Terrain& planet, SessionFiles files, SessionStoreOptions options,
               double now);

  // From the undo journal (edit::UndoJournal::setListener): one record per stroke end, undo
  // (the before-heights) and redo (the after-heights), queued for the writer (flushed to disk
  // there).
  void onCommitted(edit::JournalEvent event,
                   std::span<const edit::HeightChange> changes) noexcept override;
  // Heights changed outside the undo journal (sand settling): the rectangle's heights are
  // journaled as they are now (written, flushed to disk with the next stroke record).
  void recordRegion(const terrain::VertexBox& region) noexcept;

  // Once a frame: brings the save's copy of the heights up to date (a bounded copy) and starts
  // a save in the background when the autosave interval has passed since the last one (or one
  // was requested), something changed since, no stroke is open (a stroke is journaled only once
  // it ends) and no save is running. Returns true if it started one.
  bool tick(double now, bool strokeOpen);
  // A save in the background at the next tick that can start one (Ctrl+S).
  void requestSave() { saveRequested_ = true; }
  // Saves now and waits for it (the start, the end): the planet atomically, then the journal
  // started again for the saved heights. Throws std::runtime_error when the save failed.
  void save(double now);
  // Blocks until every queued record and a running save are on disk (tests, the end).
  void flush() { writer_.wait(); }

  const SessionFiles& files() const { return files_; }
  std::uint64_t saves() const { return generation_; }  // saves started, the first included
  std::uint64_t savesDone() const { return writer_.stats().savesDone; }
  bool saving() const { return writer_.saving(); }
  std::uint32_t recordsSinceSave() const { return writer_.recordsSinceSave(); }
  bool dirty() const { return dirty_; }
  double lastSaveMs() const { return writer_.stats().lastSaveMs; }
  double lastSaveTime() const { return lastSave_; }
  SessionWriterStats writerStats() const { return writer_.stats(); }
  // The frame loop's part of saving: the copy into the shadow per tick (ms), the longest.
  double copyMaxMs() const { return copyMaxMs_; }
  // The last disk error ("" when none); journaling goes on after the next save.
  const std::string& error();
  SessionWriter& writer() { return writer_; }

 private:
  void append(io::JournalRecordKind kind, bool sync) noexcept;
  void startSave(double now);

  terrain::Terrain& planet_;
  SessionFiles files_;
  SessionStoreOptions options_;
  HeightsShadow shadow_;
  std::vector<io::JournalHeight> scratch_;
  std::uint64_t generation_ = 0;
  double lastSave_ = 0;
  double copyMaxMs_ = 0;
  bool dirty_ = false;
  bool saveRequested_ = false;
  std::string error_;
  SessionWriter writer_;  // last: its thread stops (writing what is queued) first
};

}  // namespace ps::session
