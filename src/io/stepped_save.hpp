#pragma once
// A planet file written by a thread that must not hold its other work back for long
// (session/session_writer.hpp): the heights' CRC-32 and the file are done in steps, each
// written step flushed to disk, with a call between steps where the thread serves that work.
// The file is the one savePlanet writes (float32), replaced atomically (io/atomic_file.hpp).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

#include "io/planet_file.hpp"

namespace ps::io {

struct SteppedSave {
  std::size_t stepBytes = std::size_t(8) << 20;
  // After each step (a piece checksummed, a piece written and flushed).
  std::function<void()> between;
  // Once the complete temporary file is on disk, before it replaces the planet file; an
  // exception from it leaves the planet file as it was.
  std::function<void(std::uint32_t heightsCrc)> beforeRename;
};

// Returns the heights' checksum (heightsChecksum). Throws std::runtime_error naming the file
// when the disk refuses (the planet file is then left as it was).
std::uint32_t savePlanetInSteps(const core::Chart& chart, std::span<const float> heights,
                                terrain::ErrorRule rule, const std::filesystem::path& path,
                                const SteppedSave& steps, const PlanetSaveOptions& options = {});

}  // namespace ps::io
