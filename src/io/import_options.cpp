// The import's settings by name (heightmap_import.hpp) and its default grid.
#include <cmath>
#include <exception>
#include <limits>

#include "core/named_values.hpp"
#include "io/heightmap_import.hpp"
#include "io/import_util.hpp"

namespace ps::io {

using import_detail::levelFor;

constexpr core::NameTable<Interpolation, 2> kInterpolations{
    "interpolation", {{{Interpolation::kCubic, "cubic"}, {Interpolation::kBilinear, "bilinear"}}}};

std::string toString(Interpolation i) {
  return kInterpolations.nameOf(i);
}

Interpolation interpolationFromString(const std::string& s) {
  return kInterpolations.parse(s);
}

ChartKind chartKindFromString(const std::string& s) {
  return core::chartShapeFromString(s);
}

NoDataPolicy noDataPolicyFromString(const std::string& s) {
  constexpr core::NameTable<NoDataPolicy, 2> kPolicies{
      "no-data policy", {{{NoDataPolicy::kFill, "fill"}, {NoDataPolicy::kRefuse, "refuse"}}}};
  return kPolicies.parse(s);
}

double noDataValueFromString(const std::string& s) {
  if (s == "nan" || s == "NaN" || s == "NAN") return std::numeric_limits<double>::quiet_NaN();
  std::size_t used = 0;
  double x = 0;
  try {
    x = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (s.empty() || used != s.size() || !std::isfinite(x)) {
    throw core::InputError("--nodata-value '" + s + "' is not a finite number or nan");
  }
  return x;
}

long long defaultGridSide(ChartKind chart, int width, int height) {
  // latlong: m cells span 360 deg of longitude and 180 deg of latitude; the grid is twice as fine
  // as the image both ways, so that a round trip through it (cubic both ways) comes back within
  // the image's own precision (docs/EXPORT.md: Mars at 1440x720, 4097^2: rms 1.85 m; at 2049^2,
  // as fine as the image along the equator: 13.3 m). The octahedral chart takes the same side:
  // at 2049^2 its error per area is 11.4 m against lat-long's 15.5, at 4097^2 2.6 against 2.2
  // (docs/CHARTS.md). flat: the image's own samples.
  // torus and cylinder: the image's own columns (and a torus's rows) as cells, so that an image
  // of the grid's own size (io::resampleTube) comes back onto the same grid.
  const long long cells = core::isSphere(chart) ? std::max<long long>(2LL * width, 4LL * height)
                          : chart == ChartKind::kTorus    ? std::max<long long>(width, height)
                          : chart == ChartKind::kCylinder ? std::max<long long>(width, height - 1LL)
                                                          : std::max<long long>(width, height) - 1;
  return (1LL << levelFor(cells)) + 1;
}

}  // namespace ps::io
