#pragma once
// PlanetSculpt's own planet file (".planet"), format versions 1 and 2; docs/PLANET-FILE.md is the
// specification. A fixed 128-byte little-endian header (magic, version, chart, grid, radius or
// spacing, height encoding with scale and offset, error rule, section sizes, a CRC-32 of the
// body and one of the header), then a UTF-8 JSON metadata block, then the heights row by row.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/chart.hpp"
#include "terrain/terrain.hpp"

namespace ps::io {

// The newest version this build reads and writes (it reads every older one; it writes the oldest
// version that holds the planet's chart: 1 for lat-long and flat, 2 for octahedral).
inline constexpr std::uint32_t kPlanetFileVersion = 2;
inline constexpr std::size_t kPlanetHeaderBytes = 128;
inline constexpr std::size_t kPlanetMaxMetadataBytes = 1 << 20;

enum class HeightEncoding : std::uint32_t {
  kFloat32 = 1,  // IEEE float32 LE; metres = stored * scale + offset (the writer uses 1 and 0)
  kUint16 = 2,   // uint16 LE; metres = stored * scale + offset (quantised: smaller, lossy)
};
std::string toString(HeightEncoding e);
HeightEncoding heightEncodingFromString(const std::string& s);  // "f32" | "u16"; InputError

struct PlanetSaveOptions {
  HeightEncoding encoding = HeightEncoding::kFloat32;
  nlohmann::json metadata = nlohmann::json::object();  // stored as is (an object)
};

// What a planet file holds, checked field by field but not yet a Terrain (no bounds built).
struct PlanetData {
  std::shared_ptr<const core::Chart> chart;
  std::vector<float> heights;  // metres, row-major v * side + u
  terrain::ErrorRule rule = terrain::ErrorRule::kHybridExact;
  HeightEncoding encoding = HeightEncoding::kFloat32;
  double heightScale = 1.0, heightOffset = 0.0;
  nlohmann::json metadata = nlohmann::json::object();
};

// The file's bytes, exactly as savePlanet writes them (exposed for tests and fuzzing).
std::vector<unsigned char> encodePlanet(const core::Chart& chart, std::span<const float> heights,
                                        terrain::ErrorRule rule,
                                        const PlanetSaveOptions& options = {});

// Parses and checks a whole file image: every header field, the header and body checksums,
// the sizes, the metadata JSON, and the heights (finite, within the height limit, seam twins
// equal, pole rows one value). Throws core::InputError "<name>: <what is wrong>".
PlanetData parsePlanet(std::span<const unsigned char> bytes, const std::string& name);

// Reads and checks a file (the header first, so a lying size never allocates).
PlanetData readPlanetFile(const std::filesystem::path& path);

// readPlanetFile + the Terrain (error bounds built with the file's rule).
std::unique_ptr<terrain::Terrain> loadPlanet(const std::filesystem::path& path);

// Atomic save (io::writeAtomically: temporary file, fsync, rename, fsync of the directory): a
// crash or kill at any moment leaves the previous file intact. Throws std::runtime_error
// naming the file when the disk refuses.
void savePlanet(const core::Chart& chart, std::span<const float> heights, terrain::ErrorRule rule,
                const std::filesystem::path& path, const PlanetSaveOptions& options = {});
void savePlanet(const terrain::Terrain& terrain, const std::filesystem::path& path,
                const PlanetSaveOptions& options = {});

// The header and metadata block savePlanet writes before float32 heights (scale 1, offset 0)
// whose CRC-32 (heightsChecksum, little-endian bytes) is `heightsCrc`: for writers that stream
// the heights themselves (io/stepped_save.hpp).
struct PlanetPrologue {
  std::array<unsigned char, kPlanetHeaderBytes> header{};
  std::string metadata;
};
PlanetPrologue planetPrologue(const core::Chart& chart, terrain::ErrorRule rule,
                              std::uint32_t heightsCrc, const PlanetSaveOptions& options = {});

// True when the first bytes are a planet file's magic.
bool looksLikePlanetFile(std::span<const unsigned char> firstBytes);

}  // namespace ps::io
