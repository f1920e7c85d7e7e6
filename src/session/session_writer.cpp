#include "session/session_writer.hpp"

#include <algorithm>
#include <exception>

#include "io/stepped_save.hpp"

namespace ps::session {

namespace {
double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

SessionWriter::SessionWriter(std::filesystem::path planetFile, std::filesystem::path journalFile,
                             std::shared_ptr<const core::Chart> chart, SessionWriterOptions options)
    : planetFile_(std::move(planetFile)),
      journalFile_(std::move(journalFile)),
      chart_(std::move(chart)),
      options_(options),
      thread_([this](std::stop_token stop) { run(stop); }) {}

SessionWriter::~SessionWriter() {
  thread_.request_stop();
  if (thread_.joinable()) thread_.join();
}

void SessionWriter::push(Job job) {
  {
    std::lock_guard lock(mutex_);
    jobs_.push_back(std::move(job));
  }
  wake_.notify_one();
}

void SessionWriter::record(io::JournalRecordKind kind, std::vector<io::JournalHeight> heights,
                           bool sync) noexcept {
  try {
    Job job;
    job.record = {kind, std::move(heights)};
    job.sync = sync;
    job.queued = std::chrono::steady_clock::now();
    push(std::move(job));
  } catch (const std::exception& e) {
    // Out of memory for the queue: the records after a missing one would recover a wrong
    // planet; the writer stops journaling until the next save, as after a disk error.
    std::lock_guard lock(mutex_);
    error_ = std::string("cannot queue a journal record: ") + e.what();
  }
}

bool SessionWriter::save(std::span<const float> heights, terrain::ErrorRule rule,
                         std::uint64_t generation) {
  if (saving_.exchange(true, std::memory_order_acq_rel)) return false;
  Job job;
  job.isSave = true;
  job.heights = heights;
  job.rule = rule;
  job.generation = generation;
  job.queued = std::chrono::steady_clock::now();
  push(std::move(job));
  return true;
}

void SessionWriter::wait() {
  std::unique_lock lock(mutex_);
  idle_.wait(lock, [&] { return jobs_.empty() && !busy_; });
}

SessionWriterStats SessionWriter::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

std::string SessionWriter::takeError() {
  std::lock_guard lock(mutex_);
  return std::exchange(error_, std::string());
}

void SessionWriter::fail(const std::string& what) {
  std::lock_guard lock(mutex_);
  error_ = what;
}

void SessionWriter::run(std::stop_token stop) {
  std::unique_lock lock(mutex_);
  for (;;) {
    // On a stop request the queue is still written out before the thread ends.
    wake_.wait(lock, stop, [&] { return !jobs_.empty(); });
    if (jobs_.empty()) return;
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    busy_ = true;
    lock.unlock();
    if (job.isSave)
      doSave(job);
    else
      write(job);
    lock.lock();
    busy_ = false;
    if (jobs_.empty()) idle_.notify_all();
  }
}

void SessionWriter::write(Job& job) {
  if (keeping_) kept_.push_back(job.record);  // for the journal the running save starts
  recordsSinceSave_.fetch_add(1);
  if (!journal_) return;  // stopped after a disk error, until the next save
  const auto t0 = std::chrono::steady_clock::now();
  try {
    journal_->append(job.record.kind, job.record.heights, job.sync);
  } catch (const std::exception& e) {
    // A missing record would make the later ones wrong: stop journaling until the next save
    // (the records before it still recover a consistent earlier state).
    journal_.reset();
    fail(std::string(e.what()) + "; journaling stopped until the next save");
    return;
  }
  const double ms = msSince(t0), lag = msSince(job.queued);
  std::lock_guard lock(mutex_);
  ++stats_.records;
  stats_.recordTotalMs += ms;
  stats_.recordMaxMs = std::max(stats_.recordMaxMs, ms);
  stats_.recordLagMaxMs = std::max(stats_.recordLagMaxMs, lag);
}

// Between a save's steps: the records queued since, in order. Only records can be queued
// behind a running save (SessionWriter::save refuses a second one).
void SessionWriter::serviceRecords() {
  for (;;) {
    Job job;
    {
      std::lock_guard lock(mutex_);
      if (jobs_.empty() || jobs_.front().isSave) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    write(job);
  }
}

void SessionWriter::doSave(const Job& job) {
  const auto t0 = std::chrono::steady_clock::now();
  // The first record the new planet file will not hold: records after this one are kept for
  // the journal that continues it.
  const std::uint32_t resumeAt = journal_ ? journal_->records() : 0;
  keeping_ = true;
  kept_.clear();
  auto step = [&](SaveStep s) {
    if (hook_) hook_(s);
  };
  try {
    io::SteppedSave steps;
    steps.stepBytes = options_.saveStepBytes;
    steps.between = [&] {
      step(SaveStep::kStep);
      serviceRecords();
    };
    steps.beforeRename = [&](std::uint32_t crc) {
      serviceRecords();
      if (journal_) try {
          journal_->appendMark({crc, resumeAt, job.generation});
        } catch (const std::exception& e) {
          journal_.reset();
          fail(std::string(e.what()) + "; journaling stopped until the next save");
        }
      step(SaveStep::kMarked);
    };
    const std::uint32_t crc =
        io::savePlanetInSteps(*chart_, job.heights, job.rule, planetFile_, steps);
    step(SaveStep::kReplaced);
    serviceRecords();
    io::JournalBase base;
    base.side = std::uint32_t(chart_->grid().side());
    base.radius = chart_->sphereRadius();
    base.heightsCrc = crc;
    base.generation = job.generation;
    try {
      journal_ = std::make_unique<io::StrokeJournalWriter>(journalFile_, base, kept_);
      recordsSinceSave_.store(std::uint32_t(kept_.size()));
      step(SaveStep::kRestarted);
    } catch (const std::exception& e) {
      // The old journal (if it still takes records) goes on: its mark makes it continue the new
      // planet file.
      fail(std::string("the journal was not started again after the save: ") + e.what());
    }
    const double ms = msSince(t0);
    std::lock_guard lock(mutex_);
    ++stats_.savesDone;
    stats_.lastSaveMs = ms;
    stats_.saveMaxMs = std::max(stats_.saveMaxMs, ms);
  } catch (const std::exception& e) {
    fail(std::string("save failed: ") + e.what());
  }
  keeping_ = false;
  kept_.clear();
  saving_.store(false, std::memory_order_release);
}

}  // namespace ps::session
