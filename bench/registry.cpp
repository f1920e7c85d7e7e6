#include "bench/bench.hpp"

namespace ps::bench {

std::map<std::string, RegisteredBench>& registeredBenchmarks() {
  static std::map<std::string, RegisteredBench> all;
  return all;
}

}  // namespace ps::bench
