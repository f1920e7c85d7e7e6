// `planetsculpt bench export`: view-independent meshes of flat heightmaps (a real SRTM tile
// with its holes filled, and a synthetic fractal) swept over the requested error, against
// Martini (@mapbox/martini, run with node) on the same heights in the same run. For both tools
// the true error is measured here, against every full-resolution vertex, with the same code.
//
// The TIN rows (tool planetsculpt-tin, delatin, compare-tin, control-map) are described in
// bench/bench_export_tin.cpp.
//
// JSON lines:
//   tool planetsculpt | martini: heightmap, grid, requested_error_m, true_error_m, triangles,
//     ms (error table build + mesh), build_ms, mesh_ms (medians of warm repeats, like Martini's),
//     first_mesh_ms (planetsculpt: the request's first pass, touching fresh memory);
//   tool compare: for each planetsculpt request E, the fewest triangles Martini needs for a
//     true error <= E (its threshold swept finely below E) and the time it takes.
// Martini is single-threaded JavaScript; our bounds build is measured on one core (the
// algorithms compared) and on two (what `planetsculpt export` takes on this machine).
#include <omp.h>
#include <unistd.h>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>

#include "app/build_paths.hpp"
#include "bench/bench.hpp"
#include "bench/bench_export.hpp"
#include "bench/bench_util.hpp"
#include "core/flat_chart.hpp"
#include "io/height_image.hpp"
#include "io/heightmap_import.hpp"
#include "terrain/error_mesher.hpp"
#include "terrain/screen_error.hpp"

namespace ps::bench {

namespace {

namespace fs = std::filesystem;

// fBm of value noise (8 octaves, persistence 0.5), scaled to 0 .. 2000 m: a rough synthetic
// terrain whose features are not aligned with the bintree.
Heightmap fractal(int side, std::uint32_t seed) {
  Heightmap h;
  h.name = "synthetic-fbm";
  h.side = side;
  h.dx = h.dy = 30.0;
  std::mt19937 rng(seed);
  const int lattice = 257;
  std::vector<double> noise(std::size_t(lattice) * lattice);
  for (double& x : noise) x = std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
  auto value = [&](double x, double y) {
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    const double sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
    auto at = [&](int xi, int yi) {
      return noise[std::size_t(((yi % lattice) + lattice) % lattice) * lattice +
                   std::size_t(((xi % lattice) + lattice) % lattice)];
    };
    return (1 - sy) * ((1 - sx) * at(x0, y0) + sx * at(x0 + 1, y0)) +
           sy * ((1 - sx) * at(x0, y0 + 1) + sx * at(x0 + 1, y0 + 1));
  };
  h.heights.resize(std::size_t(side) * side);
  for (int v = 0; v < side; ++v) {
    for (int u = 0; u < side; ++u) {
      double sum = 0, amp = 1, freq = 4.0 / (side - 1);
      for (int o = 0; o < 8; ++o) {
        sum += amp * value(u * freq + 17.3 * o, v * freq + 5.1 * o);
        amp *= 0.5;
        freq *= 2.0;
      }
      h.heights[std::size_t(v) * side + u] = float(sum);
    }
  }
  const auto [lo, hi] = std::minmax_element(h.heights.begin(), h.heights.end());
  const float a = *lo, span = *hi - *lo;
  for (float& x : h.heights) x = 2000.0f * (x - a) / span;
  h.info = {{"source", "fBm value noise, seed " + std::to_string(seed)}, {"relief_m", 2000}};
  return h;
}

// The top-left side x side window of the SRTM tile (Mount Rainier is in it), holes filled.
std::optional<Heightmap> srtm(int side) {
  const fs::path file =
      ps::app::sourceDir() / ".." / "shared" / "data" / "dem" / "srtm_mt_rainier_90m.tif";
  if (!fs::exists(file)) {
    std::cerr << "bench export: " << file.string() << " is absent; the real heightmap is skipped\n";
    return std::nullopt;
  }
  io::HeightImage img = io::readHeightImage(file);
  if (img.width < side || img.height < side) return std::nullopt;
  io::HeightImage crop = img;
  crop.width = crop.height = side;
  crop.values.resize(std::size_t(side) * side);
  for (int y = 0; y < side; ++y) {
    std::copy_n(img.values.begin() + std::ptrdiff_t(y) * img.width, side,
                crop.values.begin() + std::ptrdiff_t(y) * side);
  }
  io::ImportOptions o;
  o.chart = io::ChartKind::kFlat;
  o.gridSide = side;
  const io::ImportResult r = io::importHeightImage(std::move(crop), o, file.string());
  const auto* flat = dynamic_cast<const core::FlatChart*>(r.planet.chart.get());
  Heightmap h;
  h.name = "srtm-rainier";
  h.side = side;
  h.dx = flat->dx();
  h.dy = flat->dy();
  h.heights = r.planet.heights;
  h.info = {{"source", "srtm_mt_rainier_90m.tif, pixels [0, " + std::to_string(side) + ")^2"},
            {"nodata_filled", r.noDataPixels}};
  return h;
}

// Runs scripts/martini/mesh.mjs; "" and a reason on stderr when it cannot.
std::string runMartini(const Heightmap& h, const std::vector<double>& thresholds, int repeats,
                       const fs::path& work) {
  const fs::path dir = ps::app::sourceDir() / "scripts" / "martini";
  if (!peerMesherReady("@mapbox/martini")) return "";
  const fs::path heights = writeHeightsF32(h, work), result = work / (h.name + ".martini.jsonl");
  std::string csv;
  for (const double t : thresholds) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%.6g", csv.empty() ? "" : ",", t);
    csv += buf;
  }
  const std::string cmd = "node '" + (dir / "mesh.mjs").string() + "' '" + heights.string() + "' " +
                          std::to_string(h.side) + " " + csv + " '" + result.string() + "' " +
                          std::to_string(repeats);
  if (std::system(cmd.c_str()) != 0) {
    std::cerr << "bench export: node " << (dir / "mesh.mjs").string()
              << " failed; Martini is skipped\n";
    return "";
  }
  return result.string();
}

}  // namespace

bool peerMesherReady(const std::string& module) {
  const fs::path dir = ps::app::sourceDir() / "scripts" / "martini";
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    std::cerr << "bench export: node is not installed; " << module << " is skipped\n";
    return false;
  }
  if (fs::exists(dir / "node_modules" / module)) return true;
  if (std::system("command -v npm >/dev/null 2>&1") != 0) {
    std::cerr << "bench export: npm is not installed and " << module << " is absent; skipped\n";
    return false;
  }
  std::cerr << "bench export: npm install in " << dir.string() << "\n";
  const std::string cmd =
      "cd '" + dir.string() + "' && npm install --no-audit --no-fund --silent >&2";
  if (std::system(cmd.c_str()) != 0 || !fs::exists(dir / "node_modules" / module)) {
    std::cerr << "bench export: npm install failed (offline?); " << module << " is skipped\n";
    return false;
  }
  return true;
}

fs::path writeHeightsF32(const Heightmap& h, const fs::path& work) {
  const fs::path file = work / (h.name + ".f32");
  if (!fs::exists(file)) {
    std::ofstream f(file, std::ios::binary);
    f.write(reinterpret_cast<const char*>(h.heights.data()),
            std::streamsize(h.heights.size() * sizeof(float)));
  }
  return file;
}

void writeSkippedPeerRow(const std::string& tool, const Heightmap& h, std::ostream& out) {
  out << nlohmann::json{{"bench", "export"},
                        {"tool", tool},
                        {"heightmap", h.name},
                        {"skipped", true}}
             .dump()
      << std::endl;
}

namespace {

struct OurMesh {
  int threads;
  double request, trueError, ms;
  std::size_t triangles;
};
struct MartiniMesh {
  double threshold, trueError, ms;
  std::size_t triangles;
};

// Our bounds build on one core (what compares with Martini's one) and on two (what
// `planetsculpt export` uses on this machine); the mesh pass is single-threaded. One mesher and
// one mesh for the whole sweep, as Martini keeps its index table in its Martini object: repeats
// then compare warm processes. The first, cold pass of each request (fresh pages while the mesh
// is larger than any before) is reported beside the median.
std::vector<OurMesh> benchOurs(const Heightmap& h, terrain::Terrain& t,
                               const std::vector<double>& requests, int repeats,
                               const std::string& grid, std::ostream& out) {
  std::map<int, double> buildMs;
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    std::vector<double> builds;
    for (int r = 0; r < repeats; ++r)
      builds.push_back(timeMs([&] {
        t.rebuildBounds(terrain::ErrorRule::kHybridExact, terrain::BoundsContent::kErrorsOnly);
      }));
    buildMs[threads] = median(builds);
  }
  omp_set_num_threads(1);
  std::vector<OurMesh> ours;
  terrain::ErrorMesher mesher;
  terrain::Mesh mesh;
  for (const double e : requests) {
    std::vector<double> ms;
    const double coldMs = timeMs([&] { mesher.mesh(t, e, mesh); });
    for (int r = 0; r < repeats; ++r) ms.push_back(timeMs([&] { mesher.mesh(t, e, mesh); }));
    const double trueErr = terrain::measureTrueError(t, mesh);
    for (const auto& [threads, build] : buildMs) {
      ours.push_back({threads, e, trueErr, build + median(ms), mesh.triangleCount()});
      out << nlohmann::json{{"bench", "export"},
                            {"tool", "planetsculpt"},
                            {"heightmap", h.name},
                            {"grid", grid},
                            {"rule", "hybrid-exact"},
                            {"threads", threads},
                            {"requested_error_m", e},
                            {"true_error_m", trueErr},
                            {"triangles", mesh.triangleCount()},
                            {"ms", build + median(ms)},
                            {"build_ms", build},
                            {"mesh_ms", median(ms)},
                            {"first_mesh_ms", coldMs},
                            {"info", h.info}}
                 .dump()
          << std::endl;
    }
  }
  return ours;
}

// Martini's meshes (scripts/martini/mesh.mjs's JSON lines), each measured against every sample
// as ours are. None, with a "skipped" row, when node or the package is missing.
std::optional<std::vector<MartiniMesh>> benchMartini(const Heightmap& h, const terrain::Terrain& t,
                                                     const std::vector<double>& thresholds,
                                                     int repeats, const fs::path& work,
                                                     const std::string& grid, std::ostream& out) {
  const std::string martiniJson = runMartini(h, thresholds, repeats, work);
  if (martiniJson.empty()) {
    writeSkippedPeerRow("martini", h, out);
    return std::nullopt;
  }
  std::ifstream f(martiniJson);
  std::string text;
  std::getline(f, text);
  const nlohmann::json m = nlohmann::json::parse(text);
  const double martiniBuild = median(m["build_ms"].get<std::vector<double>>());
  std::vector<MartiniMesh> theirs;
  const auto gside = std::uint64_t(h.side);
  while (std::getline(f, text)) {
    const nlohmann::json theirMesh = nlohmann::json::parse(text);
    const auto verts = theirMesh["vertices"].get<std::vector<std::uint32_t>>();
    const auto tris = theirMesh["triangles"].get<std::vector<std::uint32_t>>();
    // Martini's triangle (a, b, c) has its right angle at c; the measure wants it first.
    terrain::Mesh tm;
    for (std::size_t i = 0; i + 1 < verts.size(); i += 2)
      tm.gridIndex.push_back(std::uint64_t(verts[i + 1]) * gside + verts[i]);
    tm.positions.assign(tm.gridIndex.size(), Eigen::Vector3f::Zero());
    for (std::size_t k = 0; k + 2 < tris.size(); k += 3) {
      tm.indices.insert(tm.indices.end(), {tris[k + 2], tris[k], tris[k + 1]});
    }
    const double trueErr = terrain::measureTrueError(t, tm);
    const double meshMs = median(theirMesh["mesh_ms"].get<std::vector<double>>());
    const double e = theirMesh["max_error"].get<double>();
    theirs.push_back({e, trueErr, martiniBuild + meshMs, tm.triangleCount()});
    out << nlohmann::json{{"bench", "export"},
                          {"tool", "martini"},
                          {"heightmap", h.name},
                          {"grid", grid},
                          {"requested_error_m", e},
                          {"true_error_m", trueErr},
                          {"true_over_requested", trueErr / e},
                          {"triangles", tm.triangleCount()},
                          {"ms", martiniBuild + meshMs},
                          {"build_ms", martiniBuild},
                          {"mesh_ms", meshMs},
                          {"init_ms", m["init_ms"]}}
               .dump()
        << std::endl;
  }
  return theirs;
}

// At equal *true* error: Martini's cheapest mesh whose measured error meets each request.
void compareAtEqualError(const Heightmap& h, const std::string& grid,
                         const std::vector<OurMesh>& ours, const std::vector<MartiniMesh>& theirs,
                         std::ostream& out) {
  for (const OurMesh& o : ours) {
    const MartiniMesh* best = nullptr;
    for (const MartiniMesh& th : theirs) {
      if (th.trueError <= o.request && (!best || th.triangles < best->triangles)) best = &th;
    }
    nlohmann::json line = {{"bench", "export"},
                           {"tool", "compare"},
                           {"heightmap", h.name},
                           {"grid", grid},
                           {"threads", o.threads},
                           {"true_error_bound_m", o.request},
                           {"planetsculpt_triangles", o.triangles},
                           {"planetsculpt_true_error_m", o.trueError},
                           {"planetsculpt_ms", o.ms}};
    if (best) {
      line["martini_threshold_m"] = best->threshold;
      line["martini_triangles"] = best->triangles;
      line["martini_true_error_m"] = best->trueError;
      line["martini_ms"] = best->ms;
      line["triangles_ratio"] = double(o.triangles) / double(best->triangles);
      line["time_ratio"] = o.ms / best->ms;
    } else {
      line["martini_triangles"] = nullptr;  // no swept threshold met this bound
    }
    out << line.dump() << std::endl;
  }
}

}  // namespace

void benchExport(const BenchOptions& options, std::ostream& out) {
  const int side = options.quick ? 513 : 1025;
  // --quick (CI's smoke run: rows that parse and hold, no timing to quote) times each mesh once
  // and sweeps Martini in half as many steps.
  const int repeats = options.quick ? 1 : std::max(3, options.repeats / 5);
  const std::vector<double> requests =
      options.quick ? std::vector<double>{2, 8, 32} : std::vector<double>{1, 2, 5, 10, 20, 50};
  // Martini's threshold is not a bound (its true error runs over it), so it is swept finely
  // from half the smallest request up: 2^(1/4) steps.
  const double step = std::pow(2.0, options.quick ? 0.5 : 0.25);
  std::vector<double> thresholds;
  for (double t = 0.5 * requests.front(); t <= requests.back() * 1.0001; t *= step) {
    thresholds.push_back(std::round(t * 1000) / 1000);
  }
  const fs::path work =
      fs::temp_directory_path() / ("ps_bench_export_" + std::to_string(::getpid()));
  fs::create_directories(work);

  std::vector<Heightmap> maps;
  if (auto real = srtm(side)) maps.push_back(std::move(*real));
  maps.push_back(fractal(side, 7));

  const int threadsBefore = omp_get_max_threads();
  omp_set_num_threads(1);
  for (const Heightmap& h : maps) {
    const std::string grid = std::to_string(side) + "x" + std::to_string(side);
    std::cerr << "bench export: " << h.name << " " << grid << "\n";
    // --quick: the TIN rows at the two coarser requests.
    benchExportTin(h, options.quick ? std::vector<double>{8, 32} : requests, repeats, work,
                   options.outDir, out);
    auto chart = std::make_shared<core::FlatChart>(core::GridSize::fromSide(side), h.dx, h.dy);
    terrain::Terrain t(chart, h.heights);
    const std::vector<OurMesh> ours = benchOurs(h, t, requests, repeats, grid, out);
    const auto theirs = benchMartini(h, t, thresholds, repeats, work, grid, out);
    if (theirs) compareAtEqualError(h, grid, ours, *theirs, out);
  }
  omp_set_num_threads(threadsBefore);
  benchExportPlanetTin(options.quick, out);
  benchExportPlanetOverlay(options.quick, work, out);
  std::error_code ec;
  fs::remove_all(work, ec);
}

static const BenchRegistration kExport(
    "export", "View-independent meshes and TINs against Martini and Delatin", benchExport);

}  // namespace ps::bench
