#include "edit/control_vertex.hpp"

#include <cmath>
#include <cstdio>

#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"

namespace ps::edit {

std::string describePoint(const Eigen::Vector3d& p) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.17g, %.17g, %.17g) m", p.x(), p.y(), p.z());
  return buf;
}

double nearness(const core::Chart& chart, int u, int v, const Eigen::Vector3d& p) {
  if (const auto* ll = dynamic_cast<const core::LatLongChart*>(&chart))
    return ll->direction(u, v).dot(p);
  return -(chart.position(u, v, 0.0) - p).squaredNorm();
}

namespace {

template <class Score>
core::GridPoint localSearch(const core::Chart& chart, const Eigen::Vector2d& uv, int du,
                            Score&& score) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const bool wraps = chart.wrapsU(), poles = chart.hasPoleRows();
  // The torus's rows wrap too (v = 0 is v = m): rows beyond either side are the other side's,
  // and row m is returned as row 0, its canonical twin.
  const bool wrapsV = chart.gluing().vSides == core::SideGluing::kSeam;
  const int uc = int(std::lround(uv.x())), vc = int(std::lround(uv.y()));
  core::GridPoint best{-1, -1};
  double bestScore = -INFINITY;
  auto consider = [&](int u, int v) {
    const double s = score(u, v);
    if (best.u < 0 || s > bestScore) best = {u, v}, bestScore = s;
  };
  for (int vr = wrapsV ? vc - 2 : std::max(0, vc - 2);
       vr <= (wrapsV ? vc + 2 : std::min(m, vc + 2)); ++vr) {
    const int v = wrapsV ? ((vr % m) + m) % m : vr;
    if (poles && (v == 0 || v == m)) {
      consider(0, v);
      continue;
    }
    for (int u = uc - du; u <= uc + du; ++u) {
      int w = u;
      if (wraps) {
        w = ((w % m) + m) % m;  // canonical: the seam is u = 0
      } else if (w < 0 || w > m) {
        continue;
      }
      consider(w, v);
    }
  }
  return best;
}

}  // namespace

core::GridPoint nearestVertex(const core::Chart& chart, const Eigen::Vector3d& p) {
  if (!p.allFinite())
    throw core::InputError("tool position " + describePoint(p) + " is not finite");
  auto atCentre = [&] {
    return core::InputError("tool position " + describePoint(p) +
                            " is at the planet's centre: it has no nearest surface vertex");
  };
  if (const auto* ll = dynamic_cast<const core::LatLongChart*>(&chart)) {
    // Only the direction matters: rescale so that neither tiny nor huge |p| over- or underflows.
    const double scale = p.cwiseAbs().maxCoeff();
    if (!(scale > 0.0) || p.norm() < 1e-12 * chart.sphereRadius()) throw atCentre();
    const Eigen::Vector3d q = p / scale;
    const auto uv = chart.inverse(q);
    if (!uv) throw atCentre();
    // Within a row the nearest vertex is the one of nearest longitude: round(u) or a neighbour.
    return localSearch(chart, *uv, 1, [&](int u, int v) { return ll->direction(u, v).dot(q); });
  }
  const auto uv = chart.inverse(p);
  if (!uv) throw atCentre();
  return localSearch(chart, *uv, 2,
                     [&](int u, int v) { return -(chart.position(u, v, 0.0) - p).squaredNorm(); });
}

}  // namespace ps::edit
