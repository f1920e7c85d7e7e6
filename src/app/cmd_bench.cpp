// `planetsculpt bench [NAME] [OPTIONS]`: runs the registered benchmarks (bench/), JSON lines on
// stdout; with --out DIR also PNG plots of the results (app/bench_plots.hpp). Each benchmark is a
// subcommand of `bench` with its own options (bench/bench.hpp); without a name all of them run
// with their defaults.
#include <algorithm>
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
  std::string jsonFile;
};

// One line per benchmark with options of its own, naming them: `bench --help` shows every
// setting there is, `bench NAME --help` what each one does.
std::string optionsSummary(const std::vector<std::pair<std::string, CLI::App*>>& benches) {
  std::string text =
      "Each benchmark's own options (planetsculpt bench NAME --help says what they do):";
  for (const auto& [name, command] : benches) {
    std::string line;
    for (const CLI::Option* option : command->get_options())
      if (option->get_name() != "--help") line += " " + option->get_name();
    if (!line.empty())
      text += "\n  " + name + std::string(name.size() < 12 ? 12 - name.size() : 1, ' ') +
              line.substr(1);
  }
  return text;
}

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
  sub = root.add_subcommand("bench", "Run benchmarks; one JSON object per line on stdout");
  sub->add_flag("--quick", args->options.quick, "Smaller grids, fewer repeats");
  sub->add_option("--repeats", args->options.repeats, "Timed repeats per measurement")
      ->capture_default_str();
  sub->add_option("--out", args->options.outDir, "Folder for plots and pictures");
  sub->add_option("--json", args->jsonFile, "Also append the JSON lines to this file");
  sub->require_subcommand(0, 1);
  // Each benchmark a subcommand: `bench track --scene board --quick` (the common options may
  // come before or after the name: they fall through to `bench`).
  std::vector<std::pair<std::string, CLI::App*>> commands;
  auto runs = std::make_shared<std::vector<std::pair<CLI::App*, bench::BenchFunction>>>();
  for (const auto& [name, entry] : bench::registeredBenchmarks()) {
    CLI::App* command = sub->add_subcommand(name, entry.description);
    command->fallthrough();
    command->footer(
        "Also the options of `planetsculpt bench` (--quick, --repeats, --out, --json).");
    runs->emplace_back(command, entry.registrar(*command));
    commands.emplace_back(name, command);
  }
  sub->footer("Without NAME every benchmark runs with its defaults.\n" + optionsSummary(commands));
  return [args, runs] {
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
    const bool all =
        std::none_of(runs->begin(), runs->end(), [](const auto& r) { return r.first->parsed(); });
    for (const auto& [command, run] : *runs) {
      if (all || command->parsed()) run(args->options, out);
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
