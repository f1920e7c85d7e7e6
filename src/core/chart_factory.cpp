#include "core/chart_factory.hpp"

#include <cmath>
#include <stdexcept>

#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"

namespace ps::core {

bool isSphere(ChartShape s) {
  return s == ChartShape::kLatLong || s == ChartShape::kOctahedral ||
         s == ChartShape::kOctahedralCentral;
}

std::shared_ptr<const Chart> makeChart(ChartShape shape, GridSize grid, const ChartDims& dims) {
  switch (shape) {
    case ChartShape::kLatLong:
      return std::make_shared<LatLongChart>(grid, dims.radius);
    case ChartShape::kOctahedral:
      return std::make_shared<OctahedralChart>(grid, dims.radius);
    case ChartShape::kOctahedralCentral:
      return std::make_shared<OctahedralChart>(grid, dims.radius,
                                               OctahedralChart::Mapping::kCentral);
    case ChartShape::kTorus:
      return std::make_shared<TorusChart>(grid, dims.radius, dims.minorRadius);
    case ChartShape::kCylinder:
      return std::make_shared<CylinderChart>(grid, dims.radius, dims.length);
    case ChartShape::kFlat:
      return std::make_shared<FlatChart>(grid, dims.dx, dims.dy);
  }
  throw std::logic_error("makeChart: a chart shape without a class");
}

ChartShape shapeOf(const Chart& chart) {
  return chartShapeFromString(chart.name());
}

ChartDims dimsOf(const Chart& chart) {
  ChartDims d;
  if (const auto* flat = dynamic_cast<const FlatChart*>(&chart)) {
    d.dx = flat->dx();
    d.dy = flat->dy();
  } else if (const auto* torus = dynamic_cast<const TorusChart*>(&chart)) {
    d.radius = torus->majorRadius();
    d.minorRadius = torus->minorRadius();
  } else if (const auto* tube = dynamic_cast<const CylinderChart*>(&chart)) {
    d.radius = tube->tubeRadius();
    d.length = tube->length();
  } else {
    d.radius = chart.sphereRadius();
  }
  return d;
}

double boundingRadius(const Chart& chart) {
  if (const auto* torus = dynamic_cast<const TorusChart*>(&chart))
    return torus->majorRadius() + torus->minorRadius();
  if (const auto* tube = dynamic_cast<const CylinderChart*>(&chart))
    return std::hypot(tube->tubeRadius(), 0.5 * tube->length());
  return chart.sphereRadius();  // a sphere's radius, the flat chart's 0
}

}  // namespace ps::core
