#pragma once
// The live session's disk writer (docs/LIVE.md, "The writer thread"): one thread that appends
// the stroke journal's records and saves the planet, so the frame loop never waits on the disk.
// The frame loop queues records (built on the frame thread: a stroke's changed heights) and
// saves (of a HeightsShadow it leaves alone until the save ends); the thread writes them in
// order. A save goes in steps, and the records queued meanwhile are written between the steps,
// so a stroke reaches the disk within one step's time even during a long save.
//
// The order of a save, and what a kill at each point leaves (P = planet file, J = journal):
//   1. the heights' checksum, then a temporary planet file, written and flushed step by step;
//      records queued meanwhile are appended to J and also kept in memory.
//      Kill: the old P, J with every record written: J applies to P as before.
//   2. a save mark appended to J and flushed: the new heights' checksum and the first record
//      they do not hold. Kill: the same (the mark names a file that is not P yet).
//   3. the temporary file renamed over P (and the directory flushed).
//      Kill: the new P, the old J: its mark names P's checksum; the records after the mark's
//      point continue P (Recovery finds the mark).
//   4. J replaced atomically by a journal for the new P holding the records kept since the save
//      began. Kill: the new P and J, as after any save.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "io/stroke_journal.hpp"
#include "terrain/terrain.hpp"

namespace ps::session {

struct SessionWriterOptions {
  std::size_t saveStepBytes = std::size_t(8) << 20;  // a save's step (checksum, write + flush)
};

struct SessionWriterStats {
  std::size_t records = 0;   // records written (journal appends)
  double recordTotalMs = 0;  // their write + flush time on the writer thread
  double recordMaxMs = 0;
  double recordLagMaxMs = 0;    // queued -> on disk, the longest (what a kill can lose)
  std::uint64_t savesDone = 0;  // saves that replaced the planet file
  double lastSaveMs = 0, saveMaxMs = 0;
};

// Where a save is, for tests that stop the writer there and look at the files (a kill there).
enum class SaveStep { kStep, kMarked, kReplaced, kRestarted };

class SessionWriter {
 public:
  SessionWriter(std::filesystem::path planetFile, std::filesystem::path journalFile,
                std::shared_ptr<const core::Chart> chart, SessionWriterOptions options = {});
  ~SessionWriter();  // writes what is queued, then stops
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  // Queued; appended in order (flushed to disk when `sync`). Never blocks on the disk.
  void record(io::JournalRecordKind kind, std::vector<io::JournalHeight> heights,
              bool sync) noexcept;
  // Starts a save of `heights` (generation `generation`), read by the writer until saving() is
  // false again: the caller must leave them alone until then. False (nothing queued) when a
  // save is still running: saves are not queued behind each other.
  bool save(std::span<const float> heights, terrain::ErrorRule rule, std::uint64_t generation);
  bool saving() const { return saving_.load(std::memory_order_acquire); }
  // Blocks until everything queued is on disk.
  void wait();

  std::uint32_t recordsSinceSave() const { return recordsSinceSave_.load(); }
  SessionWriterStats stats() const;
  // The last disk error ("" when none), and clears it.
  std::string takeError();
  // Tests: called on the writer thread at each step of a save, before the step's work goes on.
  void setStepHook(std::function<void(SaveStep)> hook) { hook_ = std::move(hook); }

 private:
  struct Job {
    bool isSave = false;
    io::PendingRecord record;
    bool sync = false;
    std::chrono::steady_clock::time_point queued;
    std::span<const float> heights;
    terrain::ErrorRule rule = terrain::ErrorRule::kHybridExact;
    std::uint64_t generation = 0;
  };
  void run(std::stop_token stop);
  void push(Job job);
  void write(Job& job);
  void serviceRecords();
  void doSave(const Job& job);
  void fail(const std::string& what);

  const std::filesystem::path planetFile_, journalFile_;
  const std::shared_ptr<const core::Chart> chart_;
  const SessionWriterOptions options_;
  std::function<void(SaveStep)> hook_;

  mutable std::mutex mutex_;
  std::condition_variable_any wake_;
  std::condition_variable idle_;
  std::deque<Job> jobs_;
  bool busy_ = false;
  std::string error_;
  SessionWriterStats stats_;
  std::atomic<bool> saving_{false};
  std::atomic<std::uint32_t> recordsSinceSave_{0};

  // Writer thread only.
  std::unique_ptr<io::StrokeJournalWriter> journal_;
  bool keeping_ = false;
  std::vector<io::PendingRecord> kept_;  // records queued since the running save's snapshot

  std::jthread thread_;  // last: started once everything above exists
};

}  // namespace ps::session
