// `planetsculpt bench bounds`: the paper's wedgie rule against our hybrid-exact rule on the
// default planet: build time, and triangles needed for a guaranteed error (view-independent
// meshes, true error measured against every full-resolution vertex).
#include <nlohmann/json.hpp>

#include "app/default_planet.hpp"
#include "bench/bench.hpp"
#include "bench/bench_util.hpp"
#include "terrain/error_mesher.hpp"
#include "terrain/screen_error.hpp"

namespace ps::bench {

void benchBounds(const BenchOptions& options, std::ostream& out) {
  const int level = options.quick ? 10 : 12;
  auto planet = app::makeDefaultPlanet(level, 1, core::ChartShape::kLatLong);
  const std::vector<float> heights(planet->heights().begin(), planet->heights().end());
  for (const auto rule : {terrain::ErrorRule::kWedgie, terrain::ErrorRule::kHybridExact}) {
    std::vector<double> builds;
    for (int r = 0; r < std::max(1, options.repeats / 5); ++r) {
      builds.push_back(timeMs([&] { planet->rebuildBounds(rule); }));
    }
    for (const double maxErr : {10.0, 30.0, 100.0, 300.0, 1000.0}) {
      terrain::Mesh mesh;
      const double ms = timeMs([&] { mesh = terrain::meshToError(*planet, maxErr); });
      const double trueErr = terrain::measureTrueError(*planet, mesh);
      out << nlohmann::json{{"bench", "bounds"},
                            {"grid", planet->grid().label()},
                            {"rule", terrain::toString(rule)},
                            {"build_ms", median(builds)},
                            {"requested_error_m", maxErr},
                            {"true_error_m", trueErr},
                            {"true_over_requested", trueErr / maxErr},
                            {"triangles", mesh.triangleCount()},
                            {"mesh_ms", ms}}
                 .dump()
          << std::endl;
    }
  }
}

static const BenchRegistration kBounds(
    "bounds", "The wedgie rule against hybrid-exact bounds: build time, triangles for an error",
    benchBounds);

}  // namespace ps::bench
