#pragma once
// The recorded-forces log: one CSV row per haptic tick (header first). Written on the editor
// thread from the records the loop queued (never from the haptic thread). Columns:
//   t_s, x_m, y_m, z_m (tool tip, planet frame, planet metres; empty when unknown),
//   fx_n, fy_n, fz_n (force, device frame), depth_m (device metres), repulse_n, damping_nspm,
//   ramp, touching (0/1), fault (none, device-lost, non-finite, jump, time-order, no-terrain)
#include <istream>
#include <ostream>
#include <vector>

#include "haptics/haptic_core.hpp"

namespace ps::haptics {

class ForceLogWriter {
 public:
  explicit ForceLogWriter(std::ostream& out);  // writes the header
  void write(const ForceRecord& r);
  void write(const std::vector<ForceRecord>& rs) {
    for (const ForceRecord& r : rs) write(r);
  }
  std::size_t rows() const { return rows_; }

 private:
  std::ostream& out_;
  std::size_t rows_ = 0;
};

// Reads a log written by ForceLogWriter; core::InputError naming the line for anything else.
std::vector<ForceRecord> readForceLog(std::istream& in);

}  // namespace ps::haptics
