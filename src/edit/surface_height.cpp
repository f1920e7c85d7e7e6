#include "edit/surface_height.hpp"

#include <cmath>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "edit/control_vertex.hpp"

namespace ps::edit {

std::optional<SurfaceContact> surfaceContact(const terrain::Terrain& planet,
                                             const Eigen::Vector3d& p) {
  const core::Chart& chart = planet.chart();
  if (!p.allFinite() || !chart.inverse(p)) return std::nullopt;
  const auto* torus = dynamic_cast<const core::TorusChart*>(&chart);
  const auto* tube = dynamic_cast<const core::CylinderChart*>(&chart);
  if (!torus && !tube && !(chart.sphereRadius() > 0)) return std::nullopt;  // the flat chart
  SurfaceContact c;
  try {
    c.control = nearestVertex(chart, p);
  } catch (const core::InputError&) {  // at the centre: no direction
    return std::nullopt;
  }
  const double h = planet.height(c.control.u, c.control.v);
  const double rho = std::hypot(p.x(), p.y());
  if (torus) {
    c.height = std::hypot(rho - torus->majorRadius(), p.z()) - torus->minorRadius() - h;
  } else if (tube) {
    const double beyond = std::abs(p.z()) - 0.5 * tube->length();
    const double out = rho - tube->tubeRadius() - h;
    c.height = beyond > 0 ? std::hypot(out, beyond) : out;
  } else {
    c.height = p.norm() - chart.sphereRadius() - h;
  }
  return c;
}

}  // namespace ps::edit
