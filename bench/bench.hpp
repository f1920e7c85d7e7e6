#pragma once
// Benchmarks run by `planetsculpt bench [NAME]`. Each prints one JSON object per line to `out`
// and progress to stderr. Timings are medians of repeated runs; ratios compare against a
// baseline measured in the same run.
#include <ostream>
#include <string>

namespace ps::bench {

struct BenchOptions {
  bool quick = false;  // smaller grids and fewer repeats (CI smoke runs)
  int repeats = 15;
  std::string outDir;  // where plots/PNGs go ("" = none)
};

void benchTessellate(const BenchOptions& options, std::ostream& out);
void benchDeform(const BenchOptions& options, std::ostream& out);

}  // namespace ps::bench
