#include "app/default_planet.hpp"

#include "app/progress.hpp"
#include "core/input_error.hpp"
#include "terrain/relief.hpp"

namespace ps::app {

std::unique_ptr<terrain::Terrain> makeDefaultPlanet(int gridLevel, std::uint64_t seed,
                                                    core::ChartShape shape) {
  if (!core::isSphere(shape)) {
    throw core::InputError("--chart " + core::toString(shape) +
                           ": the default planet is a sphere (latlong, octahedral or "
                           "octahedral-central)");
  }
  core::ChartDims dims;
  dims.radius = kDefaultRadiusMetres;
  auto chart = core::makeChart(shape, core::GridSize(gridLevel), dims);
  std::vector<float> heights;
  {
    Progress p("relief " + chart->grid().label());
    terrain::ReliefParams params;
    params.seed = seed;
    heights = terrain::generateRelief(*chart, params, [&](double f) { p.update(f); });
    p.done("");
  }
  Progress p("error bounds");
  auto t = std::make_unique<terrain::Terrain>(chart, std::move(heights));
  p.done(std::to_string(t->bytes() >> 20) + " MiB heights + bounds");
  return t;
}

}  // namespace ps::app
