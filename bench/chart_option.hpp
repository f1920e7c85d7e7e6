#pragma once
// `--charts`: the sphere charts a benchmark runs each of its cases on, in one run (issue 43):
// lat-long and octahedral by default, so that the default chart's figures and lat-long's are
// measured side by side on the same machine and load. Every row names its chart.
#include <string>
#include <vector>

#include "core/chart_factory.hpp"

namespace CLI {
class App;
}

namespace ps::bench {

struct ChartChoice {
  std::vector<std::string> names{"latlong", "octahedral"};
  std::vector<core::ChartShape> shapes() const;
};

// Adds `--charts latlong,octahedral` (comma-separated, each one of the two sphere charts) to a
// benchmark's subcommand.
void addChartsOption(CLI::App& command, ChartChoice& charts);

}  // namespace ps::bench
