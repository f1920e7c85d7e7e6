#pragma once
// The size multiplier of the `stress` tests (suites named Stress*): 1 in CI, k with
// PS_STRESS_SCALE=k for longer runs (`PS_STRESS_SCALE=10 ctest --preset release -L stress`).
#include <cstdlib>

namespace ps::testkit {

inline int stressScale() {
  const char* s = std::getenv("PS_STRESS_SCALE");
  const int k = s ? std::atoi(s) : 1;
  return k >= 1 ? k : 1;
}

}  // namespace ps::testkit
