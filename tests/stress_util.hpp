#pragma once
// Shared by the stress tests (tests/test_stress_*.cpp, gtest suites Stress*, ctest label
// `stress`). They run in CI with bounded sizes; the environment variable PS_STRESS_SCALE (a whole
// number >= 1, default 1) multiplies their sizes for longer runs, e.g.
//   PS_STRESS_SCALE=20 ./build/release/ps_tests --gtest_filter='Stress*'
#include <algorithm>
#include <cstdlib>
#include <string>

namespace ps::testkit {

inline int stressScale() {
  const char* s = std::getenv("PS_STRESS_SCALE");
  if (!s || !*s) return 1;
  char* end = nullptr;
  const long v = std::strtol(s, &end, 10);
  if (*end != '\0' || v < 1) return 1;  // not a whole number >= 1: the CI size
  return int(std::min<long>(v, 100000));
}

// True when built with AddressSanitizer (g++: __SANITIZE_ADDRESS__; clang: __has_feature).
constexpr bool underAsan() {
#if defined(__SANITIZE_ADDRESS__)
  return true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return true;
#else
  return false;
#endif
#else
  return false;
#endif
}

}  // namespace ps::testkit
