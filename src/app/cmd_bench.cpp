// `planetsculpt bench [NAME]`: runs the registered benchmarks (bench/), JSON lines on stdout.
#include <fstream>
#include <iostream>
#include <memory>

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
    TeeBuffer tee;
    tee.a = std::cout.rdbuf();
    tee.b = file.is_open() ? file.rdbuf() : nullptr;
    std::ostream out(&tee);
    for (const auto& [name, fn] : bench::registeredBenchmarks()) {
      if (args->name == "all" || args->name == name) fn(args->options, out);
    }
    out.flush();
    return 0;
  };
});

}  // namespace
}  // namespace ps::app
