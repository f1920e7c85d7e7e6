#include "haptics/force_log.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>

#include "core/input_error.hpp"

namespace ps::haptics {

namespace {

constexpr const char* kHeader =
    "t_s,x_m,y_m,z_m,fx_n,fy_n,fz_n,depth_m,repulse_n,damping_nspm,ramp,touching,fault";

}  // namespace

ForceLogWriter::ForceLogWriter(std::ostream& out) : out_(out) {
  out_ << kHeader << "\n";
}

void ForceLogWriter::write(const ForceRecord& r) {
  char pos[96] = "";
  if (r.tipPlanet.allFinite()) {
    std::snprintf(pos, sizeof pos, "%.10g,%.10g,%.10g", r.tipPlanet.x(), r.tipPlanet.y(),
                  r.tipPlanet.z());
  } else {
    std::snprintf(pos, sizeof pos, ",,");
  }
  char line[384];
  std::snprintf(line, sizeof line, "%.6f,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g,%d,%s\n", r.time,
                pos, r.force.x(), r.force.y(), r.force.z(), r.depth, r.repulse, r.damping, r.ramp,
                r.touching ? 1 : 0, toString(r.fault));
  out_ << line;
  ++rows_;
}

std::vector<ForceRecord> readForceLog(std::istream& in) {
  std::vector<ForceRecord> out;
  std::string line;
  if (!std::getline(in, line) || line != kHeader)
    throw core::InputError("force log: line 1 is not the header '" + std::string(kHeader) + "'");
  int lineNo = 1;
  while (std::getline(in, line)) {
    ++lineNo;
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    if (line.back() == ',') f.emplace_back();
    if (f.size() != 13)
      throw core::InputError("force log: line " + std::to_string(lineNo) + " has " +
                             std::to_string(f.size()) + " fields, not 13");
    auto num = [&](int i) {
      if (f[std::size_t(i)].empty()) return std::numeric_limits<double>::quiet_NaN();
      try {
        return std::stod(f[std::size_t(i)]);
      } catch (const std::exception&) {
        throw core::InputError("force log: line " + std::to_string(lineNo) + " field " +
                               std::to_string(i + 1) + " '" + f[std::size_t(i)] +
                               "' is not a number");
      }
    };
    ForceRecord r;
    r.time = num(0);
    r.tipPlanet = {num(1), num(2), num(3)};
    r.force = {num(4), num(5), num(6)};
    r.depth = num(7);
    r.repulse = num(8);
    r.damping = num(9);
    r.ramp = num(10);
    r.touching = f[11] == "1";
    try {
      r.fault = faultFromString(f[12]);
    } catch (const core::InputError& e) {
      throw core::InputError("force log: line " + std::to_string(lineNo) + ": " + e.what());
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace ps::haptics
