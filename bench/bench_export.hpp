#pragma once
// What `bench export`'s parts share: the heightmaps it meshes and the peers (node scripts in
// scripts/martini/) it compares with.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace ps::bench {

struct Heightmap {
  std::string name;
  int side = 0;  // side x side samples
  double dx = 1, dy = 1;
  std::vector<float> heights;  // index v * side + u
  nlohmann::json info;
};

// True when node and the npm module (e.g. "delatin", "@mapbox/martini") are ready in
// scripts/martini/ (npm-installed there on first use); else false with the reason on stderr.
bool peerMesherReady(const std::string& module);

// Writes h.heights as little-endian float32 into `work` and returns the file.
std::filesystem::path writeHeightsF32(const Heightmap& h, const std::filesystem::path& work);

// The row that says a peer (`tool`: "martini", "delatin") was not run on h: node or its package
// missing, or its script failed.
void writeSkippedPeerRow(const std::string& tool, const Heightmap& h, std::ostream& out);

// The TIN rows: our greedy and quality TINs against Delatin at each request, and paper 001's
// control-map experiment, with its picture in outDir (when not empty) (bench/bench_export_tin.cpp).
void benchExportTin(const Heightmap& h, const std::vector<double>& requests, int repeats,
                    const std::filesystem::path& work, const std::string& outDir,
                    std::ostream& out);

// Whole planets as TINs (3D error) beside the bintree export.
void benchExportPlanetTin(bool quick, std::ostream& out);

// A road stitched into Mars on both sphere charts, in its own plane and in the chart's grid
// (bench/bench_export_overlay.cpp); files in `work`.
void benchExportPlanetOverlay(bool quick, const std::filesystem::path& work, std::ostream& out);

}  // namespace ps::bench
