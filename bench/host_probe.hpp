#pragma once
// A fixed workload with no project code in it, timed beside a benchmark so that each row says
// what state the shared host was in. On the 2-core VM these benchmarks run on, other tenants
// slow the memory system for minutes at a time: a random read from a 4 MiB table takes 1.4x its
// usual time then, while register-bound arithmetic slows 1.06x. The tessellation pass moves
// with the memory system (docs/BENCHMARKS.md), so its milliseconds are read against this probe.
#include <cstdint>
#include <vector>

namespace ps::bench {

class HostMemoryProbe {
 public:
  HostMemoryProbe();
  // Median over 15 timings of 1,000,000 independent random reads from the 4 MiB table.
  double medianMs();

 private:
  std::vector<std::uint32_t> table_;
  std::vector<std::uint32_t> indices_;
};

}  // namespace ps::bench
