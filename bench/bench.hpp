#pragma once
// Benchmarks run by `planetsculpt bench [NAME]`. Each prints one JSON object per line to `out`
// and progress to stderr. Timings are medians of repeated runs; ratios compare against a
// baseline measured in the same run.
#include <map>
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
// `bench occlusion`'s hand rows (bench_occlusion_hand.cpp), after its tool rows.
void benchOcclusionHand(const BenchOptions& options, std::ostream& out);

// Benchmarks register themselves by name (one static BenchRegistration per bench file), so the
// command line lists whatever was built.
using BenchFunction = void (*)(const BenchOptions&, std::ostream&);
std::map<std::string, BenchFunction>& registeredBenchmarks();
struct BenchRegistration {
  BenchRegistration(const char* name, BenchFunction fn) { registeredBenchmarks()[name] = fn; }
};

}  // namespace ps::bench
