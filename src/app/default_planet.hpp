#pragma once
#include <cstdint>
#include <memory>

#include "terrain/terrain.hpp"

namespace ps::app {

inline constexpr double kDefaultRadiusMetres = 6372790.0;  // paper 003's planet

// The bundled default planet: the procedural relief on a lat-long chart, with progress.
std::unique_ptr<terrain::Terrain> makeDefaultPlanet(int gridLevel, std::uint64_t seed);

}  // namespace ps::app
