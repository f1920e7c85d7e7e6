#include "app/default_planet.hpp"

#include <cmath>

#include "app/progress.hpp"
#include "core/input_error.hpp"
#include "terrain/relief.hpp"

namespace ps::app {

namespace {

std::string metres(double v) {
  return core::formatNumber(v, 10) + " m";
}

double positive(const std::optional<double>& v, double fallback, const std::string& option) {
  if (!v) return fallback;
  if (!std::isfinite(*v) || !(*v > 0))
    throw core::InputError(option + " " + metres(*v) + ": must be a positive length in metres");
  return *v;
}

}  // namespace

core::ChartDims resolveDims(core::ChartShape shape, const PlanetDims& given) {
  const bool torus = shape == core::ChartShape::kTorus;
  const bool tube = shape == core::ChartShape::kCylinder;
  if (given.minorRadius && !torus)
    throw core::InputError("--minor-radius is a torus's tube radius; --chart " +
                           core::toString(shape) + " takes none");
  if (given.length && !tube)
    throw core::InputError("--length is a cylinder's length; --chart " + core::toString(shape) +
                           " takes none");
  if (shape == core::ChartShape::kFlat)
    throw core::InputError(
        "--chart flat: a new planet needs a centre to stand on the board "
        "(latlong, octahedral, octahedral-central, torus or cylinder)");
  core::ChartDims d;
  if (torus) {
    d.radius = positive(given.radius, kDefaultTorusMajorMetres, "--radius");
    d.minorRadius = positive(given.minorRadius, kDefaultTorusMinorMetres, "--minor-radius");
    if (!(d.minorRadius < d.radius)) {
      // Say which of the two was a default: the user typed only the other.
      std::string which;
      if (!given.radius) which = "; --radius defaults to " + metres(kDefaultTorusMajorMetres);
      if (!given.minorRadius)
        which = "; --minor-radius defaults to " + metres(kDefaultTorusMinorMetres);
      throw core::InputError("--minor-radius " + metres(d.minorRadius) +
                             " must be below --radius " + metres(d.radius) +
                             " (a ring torus: its tube's radius below the ring's)" + which);
    }
  } else if (tube) {
    d.radius = positive(given.radius, kDefaultCylinderRadiusMetres, "--radius");
    d.length = positive(given.length, kDefaultCylinderLengthMetres, "--length");
  } else {
    d.radius = positive(given.radius, kDefaultRadiusMetres, "--radius");
  }
  return d;
}

std::unique_ptr<terrain::Terrain> makeDefaultPlanet(int gridLevel, std::uint64_t seed,
                                                    core::ChartShape shape,
                                                    const PlanetDims& given) {
  const core::ChartDims dims = resolveDims(shape, given);
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
