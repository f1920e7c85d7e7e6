#include "app/openmp_wait.hpp"

#include <unistd.h>

#include <cstdlib>
#include <string_view>

namespace ps::app {

void settleOpenMpWaiting(int argc, char** argv) {
  if (argc < 2) return;
  const std::string_view command = argv[1];
  if (command != "live" && command != "demo" && command != "replay" && command != "bench") return;
  if (std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr) return;
  if (setenv("GOMP_SPINCOUNT", kSpinCount, 0) != 0) return;
  // Only returns when the exec failed (no /proc, say): go on with what libgomp read at load.
  execv("/proc/self/exe", argv);
}

}  // namespace ps::app
