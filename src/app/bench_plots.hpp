#pragma once
// PNG plots of benchmark results (JSON lines from `planetsculpt bench`): run time against the
// measured error, with the guaranteed bound drawn beside the measurement.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ps::app {

// Writes tessellate.png, export.png, erosion.png, track.png into `dir` for the benchmarks that
// have records; returns the files written.
std::vector<std::filesystem::path> writeBenchPlots(const std::vector<nlohmann::json>& records,
                                                   const std::filesystem::path& dir);

}  // namespace ps::app
