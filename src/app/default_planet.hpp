#pragma once
#include <cstdint>
#include <memory>
#include <optional>

#include "core/chart_factory.hpp"
#include "terrain/terrain.hpp"

namespace ps::app {

inline constexpr double kDefaultRadiusMetres = 6372790.0;  // paper 003's planet
// A new planet's chart when the user names none (`demo`, `live`, `replay` without `--planet` or
// `--chart`, `import` of an equirectangular image): the octahedral chart, no poles and cells of
// one area (issue 43; docs/CHARTS.md, "The default chart"). Planet files and session sidecars
// keep the chart they name; a sidecar that names none is lat-long (replay::SessionStart).
inline constexpr core::ChartShape kDefaultChart = core::ChartShape::kOctahedral;
// A new torus or cylinder without dimensions (docs/CHARTS.md): about the default sphere's
// bounding radius (6,300 and 6,325 km), so that the demo recording's strokes, made over that
// sphere's middle latitudes, reach the torus's outer equator and the band of the cylinder.
inline constexpr double kDefaultTorusMajorMetres = 4.5e6, kDefaultTorusMinorMetres = 1.8e6;
inline constexpr double kDefaultCylinderRadiusMetres = 6.0e6, kDefaultCylinderLengthMetres = 4.0e6;

// The default planet's dimensions as the user gave them (`--radius`, `--minor-radius`,
// `--length`; unset: the defaults above, a sphere's kDefaultRadiusMetres).
struct PlanetDims {
  std::optional<double> radius, minorRadius, length;
};
// The shape's dimensions, the defaults filled in. Throws core::InputError naming the option for
// impossible ones (not finite, not positive, --minor-radius not below --radius) and for an
// option the shape does not take (--minor-radius off a torus, --length off a cylinder).
core::ChartDims resolveDims(core::ChartShape shape, const PlanetDims& given);

// The bundled default planet: the procedural relief on a sphere of the given chart (kDefaultChart
// unless `--chart` says otherwise), a torus or a cylinder, with progress. The flat chart is
// refused (no planet stands on the board without a centre).
std::unique_ptr<terrain::Terrain> makeDefaultPlanet(int gridLevel, std::uint64_t seed,
                                                    core::ChartShape chart = kDefaultChart,
                                                    const PlanetDims& dims = {});

}  // namespace ps::app
