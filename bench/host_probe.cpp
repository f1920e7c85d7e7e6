#include "bench/host_probe.hpp"

#include <random>

#include "bench/bench_util.hpp"

namespace ps::bench {

HostMemoryProbe::HostMemoryProbe() : table_(1u << 20), indices_(1000000) {
  std::mt19937 rng(20261126);  // fixed: every run reads the same addresses
  for (auto& x : table_) x = rng();
  for (auto& i : indices_) i = rng() & std::uint32_t(table_.size() - 1);
}

double HostMemoryProbe::medianMs() {
  std::vector<double> times;
  std::uint64_t sum = 0;
  for (int k = 0; k < 15; ++k) {
    times.push_back(timeMs([&] {
      for (const std::uint32_t i : indices_) sum += table_[i];
    }));
  }
  // Keeps the reads: a sum nobody uses would let the compiler drop the loop.
  volatile std::uint64_t keep = sum;
  (void)keep;
  return median(times);
}

}  // namespace ps::bench
