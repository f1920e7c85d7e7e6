#include "app/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace ps::app {

Progress::Progress(std::string stage)
    : stage_(std::move(stage)),
      tty_(::isatty(2) != 0),
      start_(std::chrono::steady_clock::now()),
      lastPrint_(start_) {
  update(0.0);
}

Progress::~Progress() {
  if (!finished_ && tty_) std::fputc('\n', stderr);
}

void Progress::update(double fraction, const std::string& detail) {
  const int percent = int(fraction * 100.0 + 0.5);
  const auto now = std::chrono::steady_clock::now();
  const double sinceLast = std::chrono::duration<double>(now - lastPrint_).count();
  if (percent == lastPercent_ && detail.empty()) return;
  if (!tty_ && percent != 0 && sinceLast < 3.0) return;
  lastPercent_ = percent;
  lastPrint_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, tty_ ? "\r[%s] %3d%% %5.1fs %s\033[K" : "[%s] %3d%% %5.1fs %s\n",
               stage_.c_str(), percent, elapsed, detail.c_str());
  std::fflush(stderr);
}

void Progress::done(const std::string& summary) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, tty_ ? "\r[%s] done %5.1fs %s\033[K\n" : "[%s] done %5.1fs %s\n",
               stage_.c_str(), elapsed, summary.c_str());
  finished_ = true;
}

}  // namespace ps::app
