#pragma once
#include <chrono>
#include <string>

namespace ps::app {

// One status line on stderr for long work: rewritten in place on a terminal, a line every few
// seconds otherwise (so CI logs stay short).
class Progress {
 public:
  explicit Progress(std::string stage);
  ~Progress();
  void update(double fraction, const std::string& detail = "");
  void done(const std::string& summary);

 private:
  std::string stage_;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, lastPrint_;
  int lastPercent_ = -1;
};

}  // namespace ps::app
