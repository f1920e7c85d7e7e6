#pragma once
// The median of a sample, NaN for an empty one (so that any bound on it fails).
#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace ps::testkit {

inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace ps::testkit
