#include "session/planet_export.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>

#include "core/input_error.hpp"
#include "io/export.hpp"
#include "io/mesh_export.hpp"

namespace ps::session {

std::string nextExportStem(const std::filesystem::path& dir) {
  for (int i = 1; i < 100000; ++i) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "planet-%03d", i);
    bool taken = false;
    for (const char* ext : {".png", ".png.json", ".glb"})
      taken = taken || std::filesystem::exists(dir / (std::string(stem) + ext));
    if (!taken) return stem;
  }
  throw core::InputError(dir.string() + ": no free planet-NNN export name");
}

PlanetExportResult exportPlanet(const terrain::Terrain& planet, const std::filesystem::path& dir,
                                const PlanetExportOptions& o) {
  std::filesystem::create_directories(dir);
  const std::string stem = nextExportStem(dir);
  PlanetExportResult r;
  r.heightmap = dir / (stem + ".png");
  r.mesh = dir / (stem + ".glb");
  io::ExportOptions hm;
  hm.format = io::ExportFormat::kPng16;
  const bool flat = !planet.chart().wrapsU() && !planet.chart().hasPoleRows();
  if (!flat) {
    hm.height = o.heightmapHeight > 0 ? o.heightmapHeight : std::min(planet.grid().m(), 2048);
    hm.width = 2 * hm.height;
  }
  const auto s = io::exportTerrain(planet, r.heightmap, hm);
  r.sidecar = s.at("sidecar").get<std::string>();
  r.width = s.at("width").get<int>();
  r.height = s.at("height").get<int>();

  double error = o.meshMaxErrorM;
  if (error <= 0) {
    const double rounding = io::coordinateRoundingBound(planet, io::MeshFormat::kGlb);
    error = std::max(4 * rounding, 0.05 * (double(planet.maxHeight()) - planet.minHeight()));
  }
  const io::MeshExportReport m = io::exportMesh(planet, error, io::MeshFormat::kGlb, r.mesh);
  r.meshErrorM = m.requestedErrorM;
  r.triangles = m.triangles;
  return r;
}

std::string PlanetExportResult::describe() const {
  char b[64];
  std::snprintf(b, sizeof b, " (%dx%d), ", width, height);
  std::string s = "exported " + heightmap.string() + b + mesh.string();
  std::snprintf(b, sizeof b, " (%zu triangles, max error %.0f m)", triangles, meshErrorM);
  return s + b;
}

BackgroundExport::~BackgroundExport() {
  if (future_.valid()) future_.wait();
}

void BackgroundExport::start(const terrain::Terrain& planet, const std::filesystem::path& dir,
                             const PlanetExportOptions& options) {
  if (running()) throw core::InputError("an export is still running");
  auto copy = std::make_shared<const terrain::Terrain>(planet);
  future_ = std::async(std::launch::async, [copy, dir, options] {
    Outcome o;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      o.result = exportPlanet(*copy, dir, options);
    } catch (const std::exception& e) {
      o.error = e.what();
    }
    o.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return o;
  });
}

std::optional<BackgroundExport::Outcome> BackgroundExport::poll() {
  if (!future_.valid() || future_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
    return std::nullopt;
  return future_.get();
}

std::optional<BackgroundExport::Outcome> BackgroundExport::wait() {
  if (!future_.valid()) return std::nullopt;
  return future_.get();
}

}  // namespace ps::session
