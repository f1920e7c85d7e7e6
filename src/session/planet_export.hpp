#pragma once
// The live panel's export (Ctrl+E): the current planet as a 16-bit PNG heightmap with its
// sidecar and as a binary glTF mesh, into OUT/exports/ under the next free counter name
// (planet-001.png, planet-001.png.json, planet-001.glb, then planet-002.*), each file written
// atomically by the io export functions (`planetsculpt export` writes the same files).
#include <cstddef>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>
#include <string>

#include "terrain/terrain.hpp"

namespace ps::session {

struct PlanetExportOptions {
  int heightmapHeight = 0;   // pixels (width 2x); 0: min(m, 2048)
  double meshMaxErrorM = 0;  // 0: 5 % of the height range, at least 4x the GLB's rounding
};

struct PlanetExportResult {
  std::filesystem::path heightmap, sidecar, mesh;
  int width = 0, height = 0;
  double meshErrorM = 0;
  std::size_t triangles = 0;
  std::string describe() const;  // one line for the panel
};

// Throws std::runtime_error or core::InputError naming the file when a write fails.
PlanetExportResult exportPlanet(const terrain::Terrain& planet,
                                const std::filesystem::path& exportsDir,
                                const PlanetExportOptions& options = {});

// The first NNN (001, 002, ...) for which no exportsDir/planet-NNN.* file exists.
std::string nextExportStem(const std::filesystem::path& exportsDir);

// exportPlanet on a copy of the planet in a thread of its own, so the live view goes on while
// a large planet is written (seconds at 4097²). One export at a time.
class BackgroundExport {
 public:
  ~BackgroundExport();  // waits for a running export (its files are completed, not cut)
  // Copies `planet` and starts; throws core::InputError while an export is running.
  void start(const terrain::Terrain& planet, const std::filesystem::path& exportsDir,
             const PlanetExportOptions& options = {});
  bool running() const { return future_.valid(); }
  struct Outcome {
    std::optional<PlanetExportResult> result;
    std::string error;  // when it failed
    double ms = 0;      // copy excluded
  };
  // The outcome once the export has finished (once), else nothing; never blocks.
  std::optional<Outcome> poll();
  // Blocks until the running export ends (tests, the end of a session).
  std::optional<Outcome> wait();

 private:
  std::future<Outcome> future_;
};

}  // namespace ps::session
