// `planetsculpt bench [NAME]`: runs the registered benchmarks (bench/), JSON lines on stdout;
// with --out DIR also PNG plots of the results (app/bench_plots.hpp).
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/bench_plots.hpp"
#include "app/command_registry.hpp"
#include "bench/bench.hpp"

namespace ps::app {

namespace {

struct BenchArgs {
  bench::BenchOptions options;
  std::string name = "all", jsonFile;
};

// Copies everything written to it into two stream buffers (stdout and the --json file).
struct TeeBuffer : std::streambuf {
  std::streambuf* a = nullptr;
  std::streambuf* b = nullptr;
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    a->sputc(char(c));
    if (b) b->sputc(char(c));
    return c;
  }
  int sync() override {
    a->pubsync();
    if (b) b->pubsync();
    return 0;
  }
};

const CommandRegistration kBench([](CLI::App& root, CLI::App*& sub) -> CommandAction {
  auto args = std::make_shared<BenchArgs>();
  std::vector<std::string> names = {"all"};
  for (const auto& [name, fn] : bench::registeredBenchmarks()) names.push_back(name);
  sub = root.add_subcommand("bench", "Run benchmarks; one JSON object per line on stdout");
  sub->add_option("name", args->name, "Which benchmark (default: all)")
      ->check(CLI::IsMember(names));
  sub->add_flag("--quick", args->options.quick, "Smaller grids, fewer repeats");
  sub->add_option("--repeats", args->options.repeats, "Timed repeats per measurement")
      ->capture_default_str();
  sub->add_option("--out", args->options.outDir, "Folder for plots and pictures");
  sub->add_option("--json", args->jsonFile, "Also append the JSON lines to this file");
  return [args] {
    std::ofstream file;
    if (!args->jsonFile.empty()) {
      file.open(args->jsonFile, std::ios::app);
      if (!file) throw std::runtime_error("cannot open " + args->jsonFile + " for appending");
    }
    // Everything goes to stdout, the --json file and (for the plots) a copy in memory.
    std::ostringstream copy;
    TeeBuffer toFile;
    toFile.a = copy.rdbuf();
    toFile.b = file.is_open() ? file.rdbuf() : nullptr;
    TeeBuffer tee;
    tee.a = std::cout.rdbuf();
    tee.b = &toFile;
    std::ostream out(&tee);
    for (const auto& [name, fn] : bench::registeredBenchmarks()) {
      if (args->name == "all" || args->name == name) fn(args->options, out);
    }
    out.flush();
    if (!args->options.outDir.empty()) {
      std::vector<nlohmann::json> records;
      std::istringstream lines(copy.str());
      for (std::string line; std::getline(lines, line);) {
        auto j = nlohmann::json::parse(line, nullptr, false);
        if (!j.is_discarded() && j.is_object()) records.push_back(std::move(j));
      }
      for (const auto& f : writeBenchPlots(records, args->options.outDir))
        std::cerr << "bench: wrote " << f.string() << "\n";
    }
    return 0;
  };
});

}  // namespace
}  // namespace ps::app
