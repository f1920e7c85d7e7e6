#include "io/stroke_journal.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "io/atomic_file.hpp"

namespace ps::io {

namespace {

// 0x89, "PSJ", CR LF, ^Z, LF (the planet file's pattern, J for journal).
constexpr unsigned char kJournalMagic[8] = {0x89, 'P', 'S', 'J', '\r', '\n', 0x1a, '\n'};
constexpr unsigned char kRecordTag[4] = {'R', 'E', 'C', '1'};

std::uint32_t journalCrc(std::uint32_t c, const unsigned char* p, std::size_t n) {
  while (n > 0) {  // zlib takes a uInt length
    const std::size_t k = std::min<std::size_t>(n, std::size_t(1) << 30);
    c = std::uint32_t(::crc32(c, p, uInt(k)));
    p += k;
    n -= k;
  }
  return c;
}

void put32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back((unsigned char)(v >> (8 * i)));
}
void put64(std::vector<unsigned char>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back((unsigned char)(v >> (8 * i)));
}
std::uint32_t get32(const unsigned char* p) {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
         std::uint32_t(p[3]) << 24;
}
std::uint64_t get64(const unsigned char* p) {
  return std::uint64_t(get32(p)) | std::uint64_t(get32(p + 4)) << 32;
}

std::string hex(std::uint32_t v) {
  char b[9];
  std::snprintf(b, sizeof b, "%08x", v);
  return b;
}

std::string errnoText() {
  return std::system_category().message(errno);
}

}  // namespace

std::string toString(JournalRecordKind kind) {
  constexpr core::NameTable<JournalRecordKind, 5> kNames{
      "journal record kind",
      {{{JournalRecordKind::kStroke, "stroke"},
        {JournalRecordKind::kUndo, "undo"},
        {JournalRecordKind::kRedo, "redo"},
        {JournalRecordKind::kSettle, "settle"},
        {JournalRecordKind::kSaveMark, "save mark"}}}};
  // A kind read from a damaged file has no name; its number is what helps.
  if (!kNames.contains(kind)) return "record kind " + std::to_string(std::uint32_t(kind));
  return kNames.nameOf(kind);
}

std::uint32_t heightsChecksum(std::span<const float> heights) {
  std::uint32_t c = std::uint32_t(::crc32(0, nullptr, 0));
  if constexpr (std::endian::native == std::endian::little) {
    return journalCrc(c, reinterpret_cast<const unsigned char*>(heights.data()),
                      heights.size_bytes());
  } else {
    std::vector<unsigned char> le;
    le.reserve(4096);
    for (std::size_t i = 0; i < heights.size(); ++i) {
      put32(le, std::bit_cast<std::uint32_t>(heights[i]));
      if (le.size() >= 4096 || i + 1 == heights.size()) {
        c = journalCrc(c, le.data(), le.size());
        le.clear();
      }
    }
    return c;
  }
}

JournalBase journalBaseOf(const terrain::Terrain& planet, std::uint64_t generation) {
  JournalBase b;
  b.side = std::uint32_t(planet.grid().side());
  b.radius = planet.chart().sphereRadius();
  b.heightsCrc = heightsChecksum(planet.heights());
  b.generation = generation;
  return b;
}

std::vector<unsigned char> encodeJournalHeader(const JournalBase& base) {
  std::vector<unsigned char> h(kJournalMagic, kJournalMagic + 8);
  put32(h, kStrokeJournalVersion);
  put32(h, std::uint32_t(kStrokeJournalHeaderBytes));
  put32(h, base.side);
  put32(h, base.heightsCrc);
  put64(h, std::bit_cast<std::uint64_t>(base.radius));
  put64(h, base.generation);
  h.resize(kStrokeJournalHeaderBytes - 4, 0);  // reserved
  put32(h, journalCrc(0, h.data(), h.size()));
  return h;
}

void encodeJournalRecord(JournalRecordKind kind, std::uint32_t sequence,
                         std::span<const JournalHeight> heights, std::vector<unsigned char>& out) {
  const std::size_t start = out.size();
  out.insert(out.end(), kRecordTag, kRecordTag + 4);
  put32(out, std::uint32_t(kind));
  put32(out, sequence);
  put32(out, std::uint32_t(heights.size()));
  out.reserve(out.size() + 8 * heights.size() + 4);
  for (const JournalHeight& h : heights) {
    put32(out, h.index);
    put32(out, std::bit_cast<std::uint32_t>(h.height));
  }
  put32(out, journalCrc(0, out.data() + start, out.size() - start));
}

void encodeJournalMark(const JournalMark& mark, std::uint32_t sequence,
                       std::vector<unsigned char>& out) {
  const std::size_t start = out.size();
  out.insert(out.end(), kRecordTag, kRecordTag + 4);
  put32(out, std::uint32_t(JournalRecordKind::kSaveMark));
  put32(out, sequence);
  put32(out, 2);  // two 8-byte pairs, as a record's heights
  put32(out, mark.heightsCrc);
  put32(out, mark.resumeAt);
  put64(out, mark.generation);
  put32(out, journalCrc(0, out.data() + start, out.size() - start));
}

JournalContents parseStrokeJournal(std::span<const unsigned char> bytes, const std::string& name) {
  JournalContents j;
  j.fileBytes = bytes.size();
  if (bytes.empty()) throw core::InputError(name + ": empty file: not a stroke journal");
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kJournalMagic, 8) != 0)
    throw core::InputError(name + ": not a PlanetSculpt stroke journal (wrong magic bytes)");
  if (bytes.size() < kStrokeJournalHeaderBytes)
    throw core::InputError(name + ": truncated header (" + std::to_string(bytes.size()) +
                           " bytes, a journal header has " +
                           std::to_string(kStrokeJournalHeaderBytes) + ")");
  const unsigned char* h = bytes.data();
  const std::uint32_t version = get32(h + 8);
  if (version < 1 || version > kStrokeJournalVersion)
    throw core::InputError(name + ": stroke journal version " + std::to_string(version) +
                           " (this program reads versions 1 to " +
                           std::to_string(kStrokeJournalVersion) + ")");
  const std::uint32_t stored = get32(h + kStrokeJournalHeaderBytes - 4),
                      computed = journalCrc(0, h, kStrokeJournalHeaderBytes - 4);
  if (stored != computed || get32(h + 12) != kStrokeJournalHeaderBytes)
    throw core::InputError(name + ": header checksum mismatch (stored " + hex(stored) +
                           ", computed " + hex(computed) + "): the journal is corrupt");
  j.base.side = get32(h + 16);
  j.base.heightsCrc = get32(h + 20);
  j.base.radius = std::bit_cast<double>(get64(h + 24));
  j.base.generation = get64(h + 32);
  if (j.base.side < 2 || j.base.side > 32769)
    throw core::InputError(name + ": grid side " + std::to_string(j.base.side) +
                           " in the header is not a planet's");
  const std::uint64_t count = std::uint64_t(j.base.side) * j.base.side;

  std::size_t at = kStrokeJournalHeaderBytes;
  j.validBytes = at;
  auto stop = [&](const std::string& what) {
    j.warning = name + ": record " + std::to_string(j.records.size()) + " at byte " +
                std::to_string(at) + " " + what + "; ignored it and the " +
                std::to_string(bytes.size() - at) + " bytes from there on (the " +
                std::to_string(j.records.size()) + " records before it are intact)";
  };
  while (at < bytes.size()) {
    const std::size_t left = bytes.size() - at;
    const unsigned char* r = bytes.data() + at;
    if (left < 16) {
      stop("is cut short (" + std::to_string(left) + " bytes: a crash while it was written?)");
      break;
    }
    if (std::memcmp(r, kRecordTag, 4) != 0) {
      stop("does not start with a record tag (a crash while it was written?)");
      break;
    }
    const std::uint32_t kind = get32(r + 4), sequence = get32(r + 8), n = get32(r + 12);
    if (n > count) {
      stop("announces " + std::to_string(n) + " heights, more than the grid's " +
           std::to_string(count));
      break;
    }
    const std::size_t size = kStrokeJournalRecordOverhead + 8 * std::size_t(n);
    if (left < size) {
      stop("is cut short (" + std::to_string(left) + " of its " + std::to_string(size) +
           " bytes: a crash while it was written?)");
      break;
    }
    const std::uint32_t want = get32(r + size - 4), got = journalCrc(0, r, size - 4);
    if (want != got) {
      stop("fails its checksum (stored " + hex(want) + ", computed " + hex(got) + ")");
      break;
    }
    if (kind < 1 || kind > 5 || sequence != j.records.size()) {
      stop("has kind " + std::to_string(kind) + " and sequence number " + std::to_string(sequence) +
           " (expected " + std::to_string(j.records.size()) + ")");
      break;
    }
    JournalRecord rec;
    rec.kind = JournalRecordKind(kind);
    rec.sequence = sequence;
    if (rec.kind == JournalRecordKind::kSaveMark) {
      rec.mark = {get32(r + 16), get32(r + 20), get64(r + 24)};
      if (n != 2 || rec.mark.resumeAt > sequence) {
        stop("is a save mark with " + std::to_string(n) + " pairs and resume point " +
             std::to_string(rec.mark.resumeAt) + " (expected 2 pairs and at most " +
             std::to_string(sequence) + ")");
        break;
      }
      j.records.push_back(std::move(rec));
      at += size;
      j.validBytes = at;
      continue;
    }
    rec.heights.resize(n);
    bool ok = true;
    for (std::uint32_t i = 0; i < n && ok; ++i) {
      rec.heights[i].index = get32(r + 16 + 8 * std::size_t(i));
      rec.heights[i].height = std::bit_cast<float>(get32(r + 20 + 8 * std::size_t(i)));
      ok = rec.heights[i].index < count && std::isfinite(rec.heights[i].height);
    }
    if (!ok) {
      stop("holds a vertex outside the grid or a height that is not finite");
      break;
    }
    j.records.push_back(std::move(rec));
    at += size;
    j.validBytes = at;
  }
  return j;
}

JournalContents readStrokeJournal(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw core::InputError(path.string() + ": cannot open the stroke journal");
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)),
                                   std::istreambuf_iterator<char>());
  return parseStrokeJournal(bytes, path.string());
}

std::size_t heightRecordsFrom(const JournalContents& journal, std::size_t firstRecord) {
  std::size_t n = 0;
  for (std::size_t i = firstRecord; i < journal.records.size(); ++i)
    n += journal.records[i].kind != JournalRecordKind::kSaveMark;
  return n;
}

void applyJournal(const JournalContents& journal, terrain::Terrain& planet, const std::string& name,
                  std::size_t firstRecord) {
  const core::GridSize& g = planet.grid();
  if (journal.base.side != std::uint32_t(g.side()))
    throw core::InputError(name + ": the journal continues a " + std::to_string(journal.base.side) +
                           "-side grid, the planet's side is " + std::to_string(g.side()));
  auto h = planet.mutableHeights();
  int uMin = g.m(), uMax = 0, vMin = g.m(), vMax = 0;
  for (std::size_t i = firstRecord; i < journal.records.size(); ++i) {
    for (const JournalHeight& x : journal.records[i].heights) {  // a mark has none
      h[x.index] = x.height;
      const int u = int(x.index % std::uint32_t(g.side())), v = int(x.index / g.side());
      uMin = std::min(uMin, u), uMax = std::max(uMax, u);
      vMin = std::min(vMin, v), vMax = std::max(vMax, v);
    }
  }
  if (uMin <= uMax) planet.commitEdit(terrain::VertexBox{uMin, uMax, vMin, vMax});
}

bool journalAlreadyIn(const JournalContents& journal, std::span<const float> heights) {
  // Every vertex's last height in the journal: scanning backwards, the first one seen wins.
  std::vector<JournalHeight> last;
  for (const JournalRecord& r : journal.records)
    last.insert(last.end(), r.heights.begin(), r.heights.end());
  std::stable_sort(last.begin(), last.end(), [](const JournalHeight& a, const JournalHeight& b) {
    return a.index < b.index;
  });
  for (std::size_t i = 0; i < last.size(); ++i) {
    if (i + 1 < last.size() && last[i + 1].index == last[i].index) continue;  // not the last one
    if (last[i].index >= heights.size() || std::bit_cast<std::uint32_t>(heights[last[i].index]) !=
                                               std::bit_cast<std::uint32_t>(last[i].height))
      return false;
  }
  return true;
}

StrokeJournalWriter::StrokeJournalWriter(const std::filesystem::path& path, const JournalBase& base,
                                         std::span<const PendingRecord> carried)
    : path_(path), base_(base) {
  std::vector<unsigned char> header = encodeJournalHeader(base);
  for (const PendingRecord& r : carried)
    encodeJournalRecord(r.kind, sequence_++, r.heights, header);
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(header.data()), std::streamsize(header.size()));
    f.close();
    if (!f) throw std::runtime_error(path.string() + ": cannot write the stroke journal");
  });
  fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd_ < 0)
    throw std::runtime_error(path.string() +
                             ": cannot open the stroke journal for appending: " + errnoText());
  bytes_ = header.size();
}

StrokeJournalWriter::~StrokeJournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void StrokeJournalWriter::append(JournalRecordKind kind, std::span<const JournalHeight> heights,
                                 bool doSync) {
  buffer_.clear();
  encodeJournalRecord(kind, sequence_, heights, buffer_);
  writeBuffer();
  if (doSync) sync();
}

void StrokeJournalWriter::appendMark(const JournalMark& mark) {
  buffer_.clear();
  encodeJournalMark(mark, sequence_, buffer_);
  writeBuffer();
  sync();
}

void StrokeJournalWriter::writeBuffer() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = errnoText();
      // Cut back what was written of this record, so that later records stay readable.
      if (::ftruncate(fd_, off_t(bytes_)) != 0) {
      }
      throw std::runtime_error(path_.string() + ": cannot append to the stroke journal: " + why);
    }
    done += std::size_t(n);
  }
  bytes_ += buffer_.size();
  ++sequence_;
}

void StrokeJournalWriter::sync() {
  if (::fdatasync(fd_) != 0)
    throw std::runtime_error(path_.string() +
                             ": cannot flush the stroke journal to disk: " + errnoText());
}

}  // namespace ps::io
