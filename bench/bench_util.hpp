#pragma once
// Small helpers shared by the benchmarks: medians, resident memory, wall clocks.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace ps::bench {

inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

inline double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(p * double(v.size() - 1) + 0.5))];
}

// Field of /proc/self/status in MiB (VmRSS: resident now, VmHWM: peak resident).
inline double procStatusMiB(const std::string& field) {
  std::ifstream f("/proc/self/status");
  std::string key;
  while (f >> key) {
    if (key == field + ":") {
      double kb = 0;
      f >> kb;
      return kb / 1024.0;
    }
    std::getline(f, key);
  }
  return 0;
}

// A figure for a JSON row, rounded to 3 places.
inline double round3(double v) {
  return std::round(v * 1000) / 1000;
}

// Rounded to 3 or 4 places, and -1 where the figure is not finite (a ratio of nothing).
inline double round3OrMinusOne(double v) {
  return std::isfinite(v) ? round3(v) : -1;
}
inline double round4OrMinusOne(double v) {
  return std::isfinite(v) ? std::round(v * 10000) / 10000 : -1;
}

// The machine's load averages over 1, 5 and 15 minutes, as /proc/loadavg writes them.
inline std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

template <class F>
double timeMs(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// A CLI11 check: empty when `text` is a side a planet's grid can have (2^n + 1, 3 .. 16385),
// else why not (bench_live.cpp).
std::string notAGridSide(const std::string& text);

}  // namespace ps::bench
