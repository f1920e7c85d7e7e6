#pragma once
// Benchmarks run by `planetsculpt bench [NAME]`. Each prints one JSON object per line to `out`
// and progress to stderr. Timings are medians of repeated runs; ratios compare against a
// baseline measured in the same run.
#include <functional>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace ps::bench {

// The options every benchmark takes (`planetsculpt bench --help`).
struct BenchOptions {
  bool quick = false;  // smaller grids and fewer repeats (CI smoke runs)
  int repeats = 15;
  std::string outDir;  // where plots/PNGs go ("" = none)
};

// Benchmarks register themselves by name (one static BenchRegistration per bench file), so the
// command line lists whatever was built. Each is a subcommand of `bench`: a benchmark with
// settings of its own adds them to its subcommand as CLI11 options (so that `planetsculpt bench
// NAME --help` lists them and a value that does not parse or is out of range is refused by name)
// and returns the function that runs it with what was given.
using BenchFunction = std::function<void(const BenchOptions&, std::ostream&)>;
using BenchRegistrar = std::function<BenchFunction(CLI::App& command)>;

struct RegisteredBench {
  std::string description;  // one line, for `planetsculpt bench --help`
  BenchRegistrar registrar;
};
std::map<std::string, RegisteredBench>& registeredBenchmarks();

struct BenchRegistration {
  // A benchmark with options of its own.
  BenchRegistration(const char* name, const char* description, BenchRegistrar registrar) {
    registeredBenchmarks()[name] = {description, std::move(registrar)};
  }
  // A benchmark with only the common options.
  BenchRegistration(const char* name, const char* description,
                    void (*run)(const BenchOptions&, std::ostream&))
      : BenchRegistration(name, description, [run](CLI::App&) { return BenchFunction(run); }) {}
};

// `bench occlusion`'s hand rows (bench_occlusion_hand.cpp), after its tool rows.
struct HandBenchSettings {
  std::vector<std::string> testsOff;  // hand-mask tests turned off: chroma, bright, texture
  std::string recording;              // run only this recording ("" = all)
  double texelMm = 0;                 // the mask's texel (0 = the HandMaskConfig default)
};
void addHandOptions(CLI::App& command, HandBenchSettings& settings);
void benchOcclusionHand(const BenchOptions& options, const HandBenchSettings& settings,
                        std::ostream& out);

}  // namespace ps::bench
