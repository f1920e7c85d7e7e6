#pragma once
// PNG plots of benchmark results (JSON lines from `planetsculpt bench`): run time against the
// measured error, with the guaranteed bound drawn beside the measurement.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ps::app {

// A record's number at `key`; NaN where it has none (a row of another experiment).
double jsonNumber(const nlohmann::json& record, const char* key);

// Writes tessellate.png, export.png, erosion.png, track.png into `dir` for the benchmarks that
// have records; returns the files written.
std::vector<std::filesystem::path> writeBenchPlots(const std::vector<nlohmann::json>& records,
                                                   const std::filesystem::path& dir);

}  // namespace ps::app
