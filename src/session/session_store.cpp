#include "session/session_store.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <system_error>

#include "core/input_error.hpp"
#include "io/planet_file.hpp"

namespace ps::session {

namespace {
std::string hex(std::uint32_t v) {
  char b[9];
  std::snprintf(b, sizeof b, "%08x", v);
  return b;
}
}  // namespace

Recovery Recovery::inspect(const SessionFiles& files) {
  Recovery r;
  r.files_ = files;
  std::error_code ec;
  if (!std::filesystem::exists(files.journal, ec)) return r;
  const std::string jname = files.journal.string(), pname = files.planet.string();
  try {
    r.journal_ = io::readStrokeJournal(files.journal);
  } catch (const std::exception& e) {
    r.state_ = State::kRefused;
    r.message_ = std::string(e.what()) + "; not applied";
    return r;
  }
  const io::JournalContents& j = *r.journal_;
  const std::string torn = j.warning.empty() ? "" : "\n" + j.warning;
  if (j.records.empty()) {
    r.message_ = j.warning;  // kNone: nothing to recover (perhaps a torn first record)
    return r;
  }
  const std::string holds = jname + " holds " + std::to_string(j.records.size()) + " record" +
                            (j.records.size() == 1 ? "" : "s") + " (strokes, undos, redos)";
  if (!std::filesystem::exists(files.planet, ec)) {
    r.state_ = State::kRefused;
    r.message_ = holds + " for a planet file " + pname + " that does not exist; not applied" + torn;
    return r;
  }
  io::PlanetData planet;
  try {
    planet = io::readPlanetFile(files.planet);
  } catch (const std::exception& e) {
    r.state_ = State::kRefused;
    r.message_ = holds + ", but its planet cannot be read: " + e.what() + torn;
    return r;
  }
  const std::uint32_t side = std::uint32_t(planet.chart->grid().side());
  const std::uint32_t crc = io::heightsChecksum(planet.heights);
  if (side == j.base.side && crc == j.base.heightsCrc) {
    r.state_ = State::kRecoverable;
    r.message_ = holds + " newer than " + pname + " (save " + std::to_string(j.base.generation) +
                 " of that session): the last session did not end normally" + torn;
    return r;
  }
  if (side == j.base.side && io::journalAlreadyIn(j, planet.heights)) {
    r.state_ = State::kAlreadySaved;
    r.message_ = holds + " that " + pname + " already holds (saved after them); nothing to recover";
    return r;
  }
  r.state_ = State::kRefused;
  r.message_ = jname + " was written for another planet (grid side " + std::to_string(j.base.side) +
               ", heights CRC-32 " + hex(j.base.heightsCrc) + ") than " + pname + " (side " +
               std::to_string(side) + ", CRC-32 " + hex(crc) + "): not applied" + torn;
  return r;
}

std::unique_ptr<terrain::Terrain> Recovery::recover() const {
  if (state_ != State::kRecoverable)
    throw core::InputError(files_.journal.string() + ": nothing to recover (" + message_ + ")");
  auto planet = io::loadPlanet(files_.planet);
  if (io::heightsChecksum(planet->heights()) != journal_->base.heightsCrc)
    throw core::InputError(files_.planet.string() + " changed since " + files_.journal.string() +
                           " was inspected; not applied");
  io::applyJournal(*journal_, *planet, files_.journal.string());
  return planet;
}

std::filesystem::path Recovery::setAside() const {
  if (state_ == State::kNone || state_ == State::kAlreadySaved) return {};
  std::filesystem::path to = files_.journal;
  to += state_ == State::kRecoverable ? ".discarded" : ".refused";
  std::filesystem::rename(files_.journal, to);  // throws filesystem_error naming both
  return to;
}

SessionStore::SessionStore(terrain::Terrain& planet, SessionFiles files,
                           SessionStoreOptions options, double now)
    : planet_(planet), files_(std::move(files)), options_(options) {
  save(now);
}

void SessionStore::save(double now) {
  const auto t0 = std::chrono::steady_clock::now();
  // The planet first: a crash before the journal starts again leaves the old journal, whose
  // records the new planet file already holds (Recovery says kAlreadySaved).
  io::savePlanet(planet_, files_.planet);
  writer_.reset();
  ++generation_;
  writer_ = std::make_unique<io::StrokeJournalWriter>(files_.journal,
                                                      io::journalBaseOf(planet_, generation_));
  dirty_ = false;
  lastSave_ = now;
  error_.clear();
  lastSaveMs_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

bool SessionStore::tick(double now, bool strokeOpen) {
  if (options_.autosaveSeconds <= 0 || !dirty_ || strokeOpen ||
      now - lastSave_ < options_.autosaveSeconds)
    return false;
  try {
    save(now);
    return true;
  } catch (const std::exception& e) {
    lastSave_ = now;  // try again after another interval
    error_ = std::string("autosave failed: ") + e.what();
    return false;
  }
}

void SessionStore::append(io::JournalRecordKind kind, bool sync) noexcept {
  dirty_ = true;
  if (!writer_) return;  // journaling stopped after a disk error, until the next save
  try {
    const auto t0 = std::chrono::steady_clock::now();
    writer_->append(kind, scratch_, sync);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++recordsWritten_;
    recordTotalMs_ += ms;
    recordMaxMs_ = std::max(recordMaxMs_, ms);
  } catch (const std::exception& e) {
    // A missing record would make the later ones wrong: stop journaling until the next save
    // (the records before it still recover a consistent earlier state).
    error_ = std::string(e.what()) + "; journaling stopped until the next save";
    writer_.reset();
  }
}

void SessionStore::onCommitted(edit::JournalEvent event,
                               std::span<const edit::HeightChange> changes) noexcept {
  scratch_.clear();
  try {
    scratch_.reserve(changes.size());
  } catch (...) {
    error_ = "out of memory while journaling a stroke; journaling stopped until the next save";
    writer_.reset();
    dirty_ = true;
    return;
  }
  // The heights the terrain holds now, not the journal's before/after: sand settles between a
  // stroke's stamps, outside the undo journal, so a stamped vertex may have moved since its
  // last stamp (its settling records came earlier in the file and would be overwritten).
  const auto h = planet_.heights();
  for (const edit::HeightChange& c : changes) scratch_.push_back({c.index, h[c.index]});
  const bool before = event == edit::JournalEvent::kUndo;
  const io::JournalRecordKind kind = event == edit::JournalEvent::kStroke
                                         ? io::JournalRecordKind::kStroke
                                     : before ? io::JournalRecordKind::kUndo
                                              : io::JournalRecordKind::kRedo;
  append(kind, options_.syncRecords);
}

void SessionStore::recordRegion(const terrain::GridRegion& region) noexcept {
  if (region.empty()) return;
  scratch_.clear();
  const core::GridSize& g = planet_.grid();
  const auto h = planet_.heights();
  try {
    region.forEachColumnRange(g, [&](int u0, int u1) {
      for (int v = region.vBegin; v <= region.vEnd; ++v)
        for (int u = u0; u <= u1; ++u) {
          const std::size_t k = g.index(u, v);
          scratch_.push_back({std::uint32_t(k), h[k]});
        }
    });
  } catch (...) {
    error_ = "out of memory while journaling settled sand; journaling stopped until the next save";
    writer_.reset();
    dirty_ = true;
    return;
  }
  append(io::JournalRecordKind::kSettle, false);
}

}  // namespace ps::session
