#include "bench/bench.hpp"

namespace ps::bench {

std::map<std::string, BenchFunction>& registeredBenchmarks() {
  static std::map<std::string, BenchFunction> all;
  return all;
}

}  // namespace ps::bench
