#include "bench/chart_option.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>

namespace ps::bench {

std::vector<core::ChartShape> ChartChoice::shapes() const {
  std::vector<core::ChartShape> out;
  for (const std::string& name : names) {
    const core::ChartShape shape = core::chartShapeFromString(name);
    if (std::find(out.begin(), out.end(), shape) == out.end()) out.push_back(shape);
  }
  return out;
}

void addChartsOption(CLI::App& command, ChartChoice& charts) {
  command
      .add_option("--charts", charts.names,
                  "Sphere charts to run each case on, comma-separated (default latlong,octahedral)")
      ->delimiter(',')
      ->check(CLI::IsMember({"latlong", "octahedral"}));
}

}  // namespace ps::bench
