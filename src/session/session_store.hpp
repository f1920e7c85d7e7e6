#pragma once
// The live session's planet on disk (docs/LIVE.md): OUT/planet.planet, saved atomically at
// start, every `autosaveSeconds` and at the end, and OUT/planet.journal, the strokes since that
// save (io/stroke_journal.hpp), one record appended and flushed per finished stroke, undo and
// redo (heard from the edit pipeline's undo journal) and per frame of sand settling. After a
// save the journal starts again, its header naming the saved heights' checksum, so a journal is
// never applied to another planet. A crash loses at most the stroke in progress.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "edit/undo_journal.hpp"
#include "io/stroke_journal.hpp"
#include "terrain/grid_region.hpp"
#include "terrain/terrain.hpp"

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
  std::size_t records() const { return journal_ ? journal_->records.size() : 0; }
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
  std::string message_;
};

struct SessionStoreOptions {
  double autosaveSeconds = 60;  // <= 0: no autosave (saves at start, on request and at the end)
  bool syncRecords = true;      // fdatasync every stroke, undo and redo record
};

class SessionStore final : public edit::JournalListener {
 public:
  // Saves `planet` to files.planet and starts files.journal for it. `now` (s, any clock) starts
  // the autosave clock. Throws std::runtime_error naming the file when the disk refuses.
  SessionStore(terrain::Terrain& planet, SessionFiles files, SessionStoreOptions options,
               double now);

  // From the undo journal (edit::UndoJournal::setListener): one record per stroke end, undo
  // (the before-heights) and redo (the after-heights), flushed to disk.
  void onCommitted(edit::JournalEvent event,
                   std::span<const edit::HeightChange> changes) noexcept override;
  // Heights changed outside the undo journal (sand settling): the rectangle's heights are
  // journaled as they are now (written, flushed to disk at the next stroke record).
  void recordRegion(const terrain::GridRegion& region) noexcept;

  // Saves when the autosave interval has passed since the last save, something changed since
  // and no stroke is open (a stroke is journaled only once it ends). Returns true if it saved.
  bool tick(double now, bool strokeOpen);
  // Saves the planet atomically, then starts the journal again for the saved heights.
  void save(double now);

  const SessionFiles& files() const { return files_; }
  std::uint64_t saves() const { return generation_; }
  std::uint32_t recordsSinceSave() const { return writer_ ? writer_->records() : 0; }
  bool dirty() const { return dirty_; }
  double lastSaveMs() const { return lastSaveMs_; }
  double lastSaveTime() const { return lastSave_; }
  // Records written this session (all saves) and the time they took (write + flush), for the
  // log line at the end.
  std::size_t recordsWritten() const { return recordsWritten_; }
  double recordMaxMs() const { return recordMaxMs_; }
  double recordTotalMs() const { return recordTotalMs_; }
  // The last disk error while journaling ("" when none); journaling goes on with the next
  // record (the planet is still saved at the next autosave).
  const std::string& error() const { return error_; }

 private:
  void append(io::JournalRecordKind kind, bool sync) noexcept;

  terrain::Terrain& planet_;
  SessionFiles files_;
  SessionStoreOptions options_;
  std::unique_ptr<io::StrokeJournalWriter> writer_;
  std::vector<io::JournalHeight> scratch_;
  std::uint64_t generation_ = 0;
  double lastSave_ = 0;
  double lastSaveMs_ = 0;
  bool dirty_ = false;
  std::string error_;
  std::size_t recordsWritten_ = 0;
  double recordMaxMs_ = 0, recordTotalMs_ = 0;
};

}  // namespace ps::session
