#include "app/default_planet.hpp"

#include "app/progress.hpp"
#include "core/latlong_chart.hpp"
#include "terrain/relief.hpp"

namespace ps::app {

std::unique_ptr<terrain::Terrain> makeDefaultPlanet(int gridLevel, std::uint64_t seed) {
  auto chart =
      std::make_shared<core::LatLongChart>(core::GridSize(gridLevel), kDefaultRadiusMetres);
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
