#include "session/session_store.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
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
    r.baseCrc_ = crc;
    r.message_ = holds + " newer than " + pname + " (save " + std::to_string(j.base.generation) +
                 " of that session): the last session did not end normally" + torn;
    return r;
  }
  // A save made while the session went on replaced the planet file, the journal not yet
  // started again for it (session/session_writer.hpp): its mark says where the file's heights
  // end in the journal.
  for (std::size_t i = j.records.size(); side == j.base.side && i-- > 0;) {
    const io::JournalRecord& m = j.records[i];
    if (m.kind != io::JournalRecordKind::kSaveMark || m.mark.heightsCrc != crc) continue;
    r.first_ = m.mark.resumeAt;
    r.baseCrc_ = crc;
    const std::size_t after = io::heightRecordsFrom(j, r.first_);
    if (after == 0) {
      r.state_ = State::kAlreadySaved;
      r.message_ =
          holds + " that " + pname + " already holds (saved after them); nothing to recover";
      return r;
    }
    r.state_ = State::kRecoverable;
    r.message_ = jname + " holds " + std::to_string(after) + " record" + (after == 1 ? "" : "s") +
                 " (strokes, undos, redos) newer than " + pname + " (save " +
                 std::to_string(m.mark.generation) +
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
  if (io::heightsChecksum(planet->heights()) != baseCrc_)
    throw core::InputError(files_.planet.string() + " changed since " + files_.journal.string() +
                           " was inspected; not applied");
  io::applyJournal(*journal_, *planet, files_.journal.string(), first_);
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
    : planet_(planet),
      files_(std::move(files)),
      options_(options),
      shadow_(planet),
      writer_(files_.planet, files_.journal, planet.chartPtr(), options.writer) {
  save(now);
}

const std::string& SessionStore::error() {
  std::string e = writer_.takeError();
  if (!e.empty()) error_ = std::move(e);
  return error_;
}

void SessionStore::startSave(double now) {
  // The shadow equals the terrain now, and every record before this point is queued before the
  // save: the planet file will hold exactly the records queued so far.
  writer_.save(shadow_.heights(), planet_.bounds().rule(), ++generation_);
  dirty_ = false;
  saveRequested_ = false;
  lastSave_ = now;
}

void SessionStore::save(double now) {
  writer_.wait();  // a save still running: the shadow is the writer's until it ends
  shadow_.follow(planet_);
  shadow_.catchUp(planet_, SIZE_MAX);
  const std::uint64_t done = writer_.stats().savesDone;
  startSave(now);
  writer_.wait();
  if (writer_.stats().savesDone == done) {
    const std::string e = writer_.takeError();
    error_ = e;
    throw std::runtime_error(e.empty() ? files_.planet.string() + ": not saved" : e);
  }
  error_.clear();
}

bool SessionStore::tick(double now, bool strokeOpen) {
  shadow_.follow(planet_);
  if (writer_.saving()) return false;  // the shadow is the writer's until the save ends
  if (!shadow_.current()) {
    const auto t0 = std::chrono::steady_clock::now();
    shadow_.catchUp(planet_, options_.copyBytesPerTick);
    copyMaxMs_ = std::max(
        copyMaxMs_,
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  const bool due = saveRequested_ || (options_.autosaveSeconds > 0 && dirty_ &&
                                      now - lastSave_ >= options_.autosaveSeconds);
  if (!due || strokeOpen || !shadow_.current()) return false;
  startSave(now);
  return true;
}

void SessionStore::append(io::JournalRecordKind kind, bool sync) noexcept {
  dirty_ = true;
  shadow_.follow(planet_);  // often enough that the terrain still keeps every change
  writer_.record(kind, std::move(scratch_), sync);
  scratch_ = {};
}

void SessionStore::onCommitted(edit::JournalEvent event,
                               std::span<const edit::HeightChange> changes) noexcept {
  scratch_.clear();
  try {
    scratch_.reserve(changes.size());
  } catch (...) {
    error_ = "out of memory while journaling a stroke";
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

void SessionStore::recordRegion(const terrain::VertexBox& region) noexcept {
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
    error_ = "out of memory while journaling settled sand";
    dirty_ = true;
    return;
  }
  append(io::JournalRecordKind::kSettle, false);
}

}  // namespace ps::session
