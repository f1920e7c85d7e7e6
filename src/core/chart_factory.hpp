#pragma once
// Charts by name: what `--chart`, planet files and imports say a planet's surface is, and the
// chart built from it. The one place that knows every chart class, so the layers above ask for
// a shape by name instead of naming a class.
#include <memory>
#include <string>

#include "core/chart.hpp"
#include "core/named_values.hpp"

namespace ps::core {

enum class ChartShape { kLatLong, kOctahedral, kOctahedralCentral, kTorus, kCylinder, kFlat };

// The names used on the command line, in planet files (Chart::name()) and in logs.
inline constexpr NameTable<ChartShape, 6> kChartShapeNames{
    "chart",
    {{{ChartShape::kLatLong, "latlong"},
      {ChartShape::kOctahedral, "octahedral"},
      {ChartShape::kOctahedralCentral, "octahedral-central"},
      {ChartShape::kTorus, "torus"},
      {ChartShape::kCylinder, "cylinder"},
      {ChartShape::kFlat, "flat"}}}};

inline ChartShape chartShapeFromString(const std::string& s) {
  return kChartShapeNames.parse(s);
}
inline std::string toString(ChartShape s) {
  return kChartShapeNames.nameOf(s);
}

// Whether the shape is a sphere of one radius (lat-long and octahedral): equirectangular images
// map onto it and its heights are measured from that radius.
bool isSphere(ChartShape s);

// The dimensions a shape needs: a sphere its radius; a torus its major (radius) and minor
// radius; a cylinder its radius and length; a flat grid its spacing.
struct ChartDims {
  double radius = 0;
  double minorRadius = 0;  // torus
  double length = 0;       // cylinder
  double dx = 0, dy = 0;
};

// Throws InputError for dimensions the shape refuses (a non-positive radius, ...).
std::shared_ptr<const Chart> makeChart(ChartShape shape, GridSize grid, const ChartDims& dims);

// The shape and dimensions of an existing chart (its name() parsed; the dimensions asked).
ChartShape shapeOf(const Chart& chart);
ChartDims dimsOf(const Chart& chart);

// The radius of the smallest sphere about the origin that holds the surface at height 0: a
// sphere's sphereRadius() (the same double), a torus's major + minor radius, a cylinder's
// hypot(radius, length / 2); 0 for the flat chart (no centre). What the AR scene sizes a planet
// by (its displayed radius, `--planet-radius`) and what the overview camera stands back from.
double boundingRadius(const Chart& chart);

}  // namespace ps::core
