#pragma once
#include <cstdint>
#include <memory>

#include "core/chart_factory.hpp"
#include "terrain/terrain.hpp"

namespace ps::app {

inline constexpr double kDefaultRadiusMetres = 6372790.0;  // paper 003's planet

// The bundled default planet: the procedural relief on a sphere of the given chart (lat-long
// unless `--chart` says otherwise), with progress.
std::unique_ptr<terrain::Terrain> makeDefaultPlanet(
    int gridLevel, std::uint64_t seed, core::ChartShape chart = core::ChartShape::kLatLong);

}  // namespace ps::app
