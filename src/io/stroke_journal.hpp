#pragma once
// The live app's stroke journal on disk (OUT/planet.journal, docs/LIVE.md has the format): a
// header naming the planet it continues (grid side, radius, CRC-32 of its heights), then one
// record per finished stroke, undo, redo or sand-settling frame, each the heights some vertices
// hold after it, with a CRC-32 of its own. Records are appended and flushed; a crash can leave
// at most the last record torn, and a reader ignores that record (with a warning), never
// anything before it. A save made while the session goes on (session/session_writer.hpp) leaves
// a save mark in the journal: the heights' CRC-32 of the planet file it wrote and the first
// record that file does not hold, so the journal still recovers once that file replaced the old
// one and before the journal is started again for it.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "terrain/terrain.hpp"

namespace ps::io {

// Written: 2 (adds the save mark); read: 1 and 2.
inline constexpr std::uint32_t kStrokeJournalVersion = 2;
inline constexpr std::size_t kStrokeJournalHeaderBytes = 64;
inline constexpr std::size_t kStrokeJournalRecordOverhead = 20;  // 16 before the heights, 4 after

enum class JournalRecordKind : std::uint32_t {
  kStroke = 1,
  kUndo = 2,
  kRedo = 3,
  kSettle = 4,
  kSaveMark = 5,  // no heights: a JournalMark
};
std::string toString(JournalRecordKind kind);

// One vertex and the height it holds after the record.
struct JournalHeight {
  std::uint32_t index = 0;  // v * side + u
  float height = 0;
};

// The planet a journal continues: its heights, as CRC-32 over their float32 bytes (little-endian,
// row-major), and its grid and radius. `generation` counts the saves of the session (shown only).
struct JournalBase {
  std::uint32_t side = 0;
  double radius = 0;
  std::uint32_t heightsCrc = 0;
  std::uint64_t generation = 0;
  bool operator==(const JournalBase&) const = default;
};
std::uint32_t heightsChecksum(std::span<const float> heights);
JournalBase journalBaseOf(const terrain::Terrain& planet, std::uint64_t generation = 0);

// A planet file saved from the heights the journal's records up to `resumeAt` give: once that
// file replaced the one the header names, the records from `resumeAt` on (marks skipped)
// continue it.
struct JournalMark {
  std::uint32_t heightsCrc = 0;
  std::uint32_t resumeAt = 0;  // a record sequence number, at most the mark's own
  std::uint64_t generation = 0;
  bool operator==(const JournalMark&) const = default;
};

struct JournalRecord {
  JournalRecordKind kind = JournalRecordKind::kStroke;
  std::uint32_t sequence = 0;  // 0, 1, 2, ... from the header on
  std::vector<JournalHeight> heights;
  JournalMark mark;  // kSaveMark only
};

struct JournalContents {
  JournalBase base;
  std::vector<JournalRecord> records;  // the complete, intact records, in order
  std::size_t validBytes = 0;          // header + those records
  std::size_t fileBytes = 0;
  // Empty, or what was ignored after the last intact record (a record cut short by a crash,
  // a checksum mismatch), naming the file and the record.
  std::string warning;
};

// Parses a journal image. Throws core::InputError "<name>: ..." when the header is unusable
// (not a journal, unknown version, header checksum); a damaged tail is reported in `warning`.
JournalContents parseStrokeJournal(std::span<const unsigned char> bytes, const std::string& name);
JournalContents readStrokeJournal(const std::filesystem::path& path);

// The heights of `records` from `firstRecord` on (save marks skipped) written into `planet`
// (bounds updated over what changed). Throws core::InputError naming `name` when the journal's
// base is not the planet's grid.
void applyJournal(const JournalContents& journal, terrain::Terrain& planet, const std::string& name,
                  std::size_t firstRecord = 0);
// The records with heights from `firstRecord` on (save marks not counted).
std::size_t heightRecordsFrom(const JournalContents& journal, std::size_t firstRecord);

// True when `heights` already holds every vertex's last height in `records` (the journal adds
// nothing to them: e.g. a planet saved after the records, before the journal was restarted).
bool journalAlreadyIn(const JournalContents& journal, std::span<const float> heights);

// One record to write: its kind and heights (the writer numbers it).
struct PendingRecord {
  JournalRecordKind kind = JournalRecordKind::kStroke;
  std::vector<JournalHeight> heights;
};

// Appends records to a journal file. The constructor replaces `path` atomically by a file
// holding the header for `base` and `carried` (records made after the planet `base` names was
// taken, numbered from 0), flushed to disk.
class StrokeJournalWriter {
 public:
  StrokeJournalWriter(const std::filesystem::path& path, const JournalBase& base,
                      std::span<const PendingRecord> carried = {});
  ~StrokeJournalWriter();
  StrokeJournalWriter(const StrokeJournalWriter&) = delete;
  StrokeJournalWriter& operator=(const StrokeJournalWriter&) = delete;

  // One record, written with a single write(2) (so a process crash never tears it; a power
  // loss may, and readers ignore a torn last record); `sync` then fdatasync()s it to disk.
  // Throws std::runtime_error naming the file when the disk refuses.
  void append(JournalRecordKind kind, std::span<const JournalHeight> heights, bool sync);
  // A save mark (JournalMark), always flushed to disk.
  void appendMark(const JournalMark& mark);
  void sync();

  const std::filesystem::path& path() const { return path_; }
  const JournalBase& base() const { return base_; }
  std::uint32_t records() const { return sequence_; }
  std::size_t bytes() const { return bytes_; }

 private:
  std::filesystem::path path_;
  JournalBase base_;
  int fd_ = -1;
  std::uint32_t sequence_ = 0;
  std::size_t bytes_ = 0;
  std::vector<unsigned char> buffer_;
  void writeBuffer();
};

// The bytes of a record and of a header, as the writer writes them (tests).
std::vector<unsigned char> encodeJournalHeader(const JournalBase& base);
void encodeJournalRecord(JournalRecordKind kind, std::uint32_t sequence,
                         std::span<const JournalHeight> heights, std::vector<unsigned char>& out);
void encodeJournalMark(const JournalMark& mark, std::uint32_t sequence,
                       std::vector<unsigned char>& out);

}  // namespace ps::io
