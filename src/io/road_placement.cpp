#include "io/road_placement.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "io/road_poles.hpp"
#include "io/road_unfolding.hpp"

namespace ps::io {

namespace {

using core::exactNumber;
constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace

RoadFrame roadFrame(const core::Chart& chart, const std::array<double, 3>& at,
                    const std::string& name) {
  const std::string where = "--at " + exactNumber(at[0]) + "," + exactNumber(at[1]);
  RoadFrame f;
  double azimuth = 0;  // of the place about the z axis: east is the direction it grows in
  if (chart.sphereRadius() > 0) {
    if (!(std::abs(at[0]) <= 90 && std::abs(at[1]) <= 180))
      throw core::InputError(where +
                             ": latitude must be within +-90 and longitude within +-180 degrees");
    const double lat = at[0] * kDeg;
    azimuth = at[1] * kDeg;
    f.up = {std::cos(lat) * std::cos(azimuth), std::cos(lat) * std::sin(azimuth), std::sin(lat)};
    f.origin = chart.sphereRadius() * f.up;
  } else if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart)) {
    if (!(std::abs(at[0]) <= 360 && std::abs(at[1]) <= 360))
      throw core::InputError(where +
                             ": on a torus the place is AROUND,ACROSS in degrees (round "
                             "the big circle, round the tube), each within +-360");
    azimuth = at[0] * kDeg;
    const double beta = at[1] * kDeg;
    const Eigen::Vector3d out(std::cos(azimuth), std::sin(azimuth), 0);
    f.up = std::cos(beta) * out + Eigen::Vector3d(0, 0, std::sin(beta));
    f.origin = torus->majorRadius() * out + torus->minorRadius() * f.up;
  } else if (const auto* tube = dynamic_cast<const core::CylinderChart*>(&chart)) {
    if (!(std::abs(at[0]) <= 360 && std::abs(at[1]) <= 0.5 * tube->length()))
      throw core::InputError(where +
                             ": on a cylinder the place is AROUND,ALONG: degrees round "
                             "the axis (within +-360) and metres along it from its "
                             "middle (within +-" +
                             exactNumber(0.5 * tube->length()) + ")");
    azimuth = at[0] * kDeg;
    f.up = {std::cos(azimuth), std::sin(azimuth), 0};
    f.origin = tube->tubeRadius() * f.up + Eigen::Vector3d(0, 0, at[1]);
  } else {
    throw core::InputError(name +
                           ": a road is laid on a flat terrain, a sphere, a torus or a "
                           "cylinder, not on the " +
                           chart.name() + " chart");
  }
  const double heading = at[2] * kDeg, ch = std::cos(heading), sh = std::sin(heading);
  const Eigen::Vector3d east(-std::sin(azimuth), std::cos(azimuth), 0);
  const Eigen::Vector3d north = f.up.cross(east);
  // The road's +y axis points at `heading` clockwise from north, its +x axis 90 degrees further.
  f.x = east * ch - north * sh;
  f.y = north * ch + east * sh;
  return f;
}

std::array<double, 2> placeOf(const core::Chart& chart, const Eigen::Vector3d& p) {
  constexpr double kToDeg = 180.0 / std::numbers::pi;
  const double around = std::atan2(p.y(), p.x()) * kToDeg;
  if (chart.sphereRadius() > 0)
    return {std::asin(std::clamp(p.z() / p.norm(), -1.0, 1.0)) * kToDeg, around};
  if (const auto* torus = dynamic_cast<const core::TorusChart*>(&chart))
    return {around, std::atan2(p.z(), std::hypot(p.x(), p.y()) - torus->majorRadius()) * kToDeg};
  if (dynamic_cast<const core::CylinderChart*>(&chart)) return {around, p.z()};
  throw core::InputError("a road has no place on the " + chart.name() + " chart");
}

Eigen::Vector3d surfaceNormal(const core::Chart& chart, const Eigen::Vector3d& p) {
  const auto uv = chart.inverse(p);
  if (!uv) throw core::InputError("a point has no place on the " + chart.name() + " chart");
  return (chart.positionAt(uv->x(), uv->y(), 1.0) - chart.positionAt(uv->x(), uv->y(), 0.0))
      .normalized();
}

namespace {

using Mesh = RoadMesh;

double signedArea(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// Around an end of an octahedral fold (a side's midpoint, glued to itself: the sphere turns whole
// there while the grid turns half) no piece of the plane unfolds the grid, so a road whose
// footprint holds one is cut along the fold's great circle and the one across it through the
// end, and its two halves are parted along the fold's other half (the meridian's northern part,
// no glued side): they meet only across the fold, where the gluing turns one half round onto the
// other, and each lies in one quarter turn of the grid about the end.
void partAtFoldEnds(Mesh& mesh, const core::Chart& chart, double m, const RoadFrame& frame) {
  const core::Gluing g = chart.gluing();
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> ends;  // (end, a point of its fold)
  if (g.uSides == core::SideGluing::kMirror)
    for (const double u : {0.0, m})
      ends.emplace_back(chart.positionAt(u, m / 2, 0), chart.positionAt(u, m / 4, 0));
  if (g.vSides == core::SideGluing::kMirror)
    for (const double v : {0.0, m})
      ends.emplace_back(chart.positionAt(m / 2, v, 0), chart.positionAt(m / 4, v, 0));
  const double lengthScale = frame.origin.norm();
  for (const auto& [end, onFold] : ends) {
    if (!(end.dot(frame.up) > 0)) continue;
    // The end in the road's plane (through the centre), and whether a triangle holds it.
    const Eigen::Vector3d q = end * (frame.origin.dot(frame.up) / end.dot(frame.up));
    const Eigen::Vector2d e((q - frame.origin).dot(frame.x), (q - frame.origin).dot(frame.y));
    bool inside = false;
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector2d a = mesh.vertices[t[0]].head<2>(), b = mesh.vertices[t[1]].head<2>(),
                            c = mesh.vertices[t[2]].head<2>();
      const double area = signedArea(a, b, c);
      if (area != 0 && signedArea(e, b, c) / area >= -1e-9 && signedArea(a, e, c) / area >= -1e-9 &&
          signedArea(a, b, e) / area >= -1e-9)
        inside = true;  // on its border too
    }
    if (!inside) continue;
    const Eigen::Vector3d fold = end.cross(onFold).normalized();  // the fold's great circle
    const Eigen::Vector3d across = fold.cross(end).normalized();  // through the end, across it
    const auto f = [&](const Eigen::Vector3d& n) {
      return [&frame, n](const Eigen::Vector3d& p) { return n.dot(frame.at(p)); };
    };
    cutRoadAlong(mesh.vertices, mesh.triangles, f(fold));
    cutRoadAlong(mesh.vertices, mesh.triangles, f(across));
    // The vertices on the fold's circle but not on the fold (the end among them), given a twin in
    // the triangles on the fold plane's negative side.
    const double tol = 1e-9 * lengthScale;
    const double foldSide = across.dot(onFold);
    std::vector<std::int64_t> twin(mesh.vertices.size(), -1);
    for (auto& t : mesh.triangles) {
      const Eigen::Vector3d centre =
          frame.at((mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3);
      if (!(fold.dot(centre) < 0)) continue;
      for (std::uint32_t& v : t) {
        const Eigen::Vector3d p = frame.at(mesh.vertices[v]);
        const bool onCircle = std::abs(fold.dot(p)) <= tol;
        const double a = across.dot(p);
        if (!onCircle || (std::abs(a) > tol && (a > 0) == (foldSide > 0))) continue;
        if (twin[v] < 0) {
          twin[v] = std::int64_t(mesh.vertices.size());
          mesh.vertices.push_back(mesh.vertices[v]);
        }
        v = std::uint32_t(twin[v]);
      }
    }
  }
}

// Each edge whose stray (`strays`: each triangle's edges k to k + 1) is above `tolerance` and that
// is longer than `shortest`, halved at its midpoint in the road's plane, and with it the longest
// edge of every triangle that has a halved edge, until each such triangle's longest edge is
// halved (Rivara's longest-edge bisection, which keeps the triangles' angles from shrinking
// round after round: thin triangles fold over where the chart bends, near the poles); each
// triangle split into 2, 3 or 4 as 1, 2 or 3 of its edges are, turning as it did.
void halveStrayingEdges(Mesh& mesh, const std::vector<std::array<double, 3>>& strays,
                        double tolerance, double shortest,
                        const std::vector<std::pair<std::uint32_t, double>>& poles) {
  using Edge = std::pair<std::uint32_t, std::uint32_t>;
  const auto key = [](std::uint32_t a, std::uint32_t b) {
    return Edge(std::min(a, b), std::max(a, b));
  };
  const auto length = [&](const Edge& e) {
    return (mesh.vertices[e.first] - mesh.vertices[e.second]).head<2>().norm();
  };
  const auto edge = [&](const std::array<std::uint32_t, 3>& t, std::size_t k) {
    return key(t[k % 3], t[(k + 1) % 3]);
  };
  const auto longest = [&](const std::array<std::uint32_t, 3>& t) {
    // A triangle round a pole of lat-long's grid is halved from the pole (its edge across from
    // it), so that every triangle near the pole stays one of its fan: a triangle beside the pole
    // but not round it, spanning a wide angle of its meridians, would turn over in the grid.
    for (std::size_t k = 0; k < 3; ++k)
      for (const auto& pole : poles)
        if (t[(k + 2) % 3] == pole.first) return k;
    std::size_t best = 0;
    for (std::size_t k = 1; k < 3; ++k)
      if (length(edge(t, k)) > length(edge(t, best))) best = k;
    return best;
  };
  std::set<Edge> marked;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::size_t k = 0; k < 3; ++k)
      if (strays[t][k] > tolerance && length(edge(mesh.triangles[t], k)) > shortest)
        marked.insert(edge(mesh.triangles[t], k));
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& t : mesh.triangles) {
      const bool any =
          marked.count(edge(t, 0)) || marked.count(edge(t, 1)) || marked.count(edge(t, 2));
      if (any && marked.insert(edge(t, longest(t))).second) grew = true;
    }
  }
  std::map<Edge, std::uint32_t> middle;
  for (const Edge& e : marked) {
    middle[e] = std::uint32_t(mesh.vertices.size());
    const Eigen::Vector3d half = 0.5 * (mesh.vertices[e.first] + mesh.vertices[e.second]);
    mesh.vertices.push_back(half);  // (evaluated first: the push may move the vertices)
  }
  std::vector<std::array<std::uint32_t, 3>> out;
  for (const auto& t : mesh.triangles) {
    const std::size_t l = longest(t);
    const auto it = middle.find(edge(t, l));
    if (it == middle.end()) {
      out.push_back(t);
      continue;
    }
    // Halved through the longest edge's midpoint, then each half's other halved edge likewise.
    const std::uint32_t a = t[l], b = t[(l + 1) % 3], c = t[(l + 2) % 3], mid = it->second;
    const auto half = [&](std::uint32_t p, std::uint32_t q, std::uint32_t r) {
      // The triangle (p, q, r) whose edge q-r may be halved.
      const auto h = middle.find(key(q, r));
      if (h == middle.end()) {
        out.push_back({p, q, r});
      } else {
        out.push_back({p, q, h->second});
        out.push_back({p, h->second, r});
      }
    };
    half(mid, b, c);
    half(mid, c, a);
  }
  mesh.triangles = std::move(out);
}

}  // namespace

LaidRoad layRoadOnPlanet(const ObjTriangles& obj, const core::Chart& chart, double m,
                         const std::array<double, 3>& at, double toleranceM,
                         const std::string& name) {
  const RoadFrame frame = roadFrame(chart, at, name);
  const double r = chart.sphereRadius();
  // A point of the road's plane onto the surface: its grid point and the surface's point.
  const auto onto = [&](const Eigen::Vector3d& p, Eigen::Vector2d& grid, Eigen::Vector3d& surface) {
    const Eigen::Vector3d q = frame.at(p);
    const auto uv = chart.inverse(q);
    if (!uv) throw core::InputError(name + ": a road vertex has no place on the " + chart.name());
    grid = *uv;
    // Beyond a cylinder's open rim the tube goes on in the grid (the inverse clamps to the rim),
    // so that the overlay clips the road there as at a flat terrain's border.
    if (const auto* tube = dynamic_cast<const core::CylinderChart*>(&chart))
      grid.y() = (q.z() / tube->length() + 0.5) * m;
    surface = r > 0 ? Eigen::Vector3d(q.normalized() * r) : chart.positionAt(grid.x(), grid.y(), 0);
  };
  Mesh base{obj.vertices, obj.triangles};
  const std::vector<std::pair<Eigen::Vector2d, double>> polePoints = polesInPlane(chart, m, frame);
  std::vector<std::int64_t> slits;  // each pole's parting edge's end on the border (or -1)
  const std::vector<std::pair<std::uint32_t, double>> poles =
      insertPoles(base, chart, m, frame, 0.25 * toleranceM, slits, name);
  std::vector<std::size_t> turnedNearPole;  // lat-long: triangles the grid turns over (lay's)
  const auto lay = [&](const Mesh& mesh) {
    tin::Road grid;
    grid.triangles = mesh.triangles;
    std::vector<Eigen::Vector3d> onSurface;
    for (const Eigen::Vector3d& p : mesh.vertices) {
      Eigen::Vector2d g;
      Eigen::Vector3d s;
      onto(p, g, s);
      // A point cut on a glued side lies on it (the inverse leaves it a rounding off).
      for (int k = 0; k < 2; ++k)
        for (const double side : {0.0, m})
          if (std::abs(g[k] - side) < 1e-9 * m) g[k] = side;
      onSurface.push_back(s);
      grid.xy.push_back(g);
      grid.h.push_back(p.z());
    }
    for (const std::int64_t end : slits)
      if (end >= 0) unwrapRoundPole(grid, onSurface, mesh.triangles, std::uint32_t(end), m);
    const PoleFan fan = spreadPoles(grid, onSurface, mesh.triangles, poles);
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      Eigen::Vector2d g;
      Eigen::Vector3d s;
      onto(0.5 * (mesh.vertices[fan.origin[a]] + mesh.vertices[fan.origin[b]]), g, s);
      return s;
    };
    // Across a seam or an octahedral fold: the pieces on either side of it.
    UnfoldedRoad unfolded = unfoldRoad(
        grid, onSurface, midpoint, chart, m, name,
        std::any_of(slits.begin(), slits.end(), [](std::int64_t end) { return end >= 0; }));
    if (!poles.empty()) leavePoleEdgesUnjudged(unfolded, grid, fan);
    // Laid without folding over: every triangle turns the same way in the grid as in the road's
    // plane as the largest does (the gluing's moves keep the turn, so the first copy tells), but
    // for slivers turned over by less than the tolerance where the chart bends most (within a
    // kilometre or two of an octahedral pole: a few metres). A pole's filler triangles have no
    // area of their own and are not judged.
    const auto& v = mesh.vertices;
    const auto& xy = unfolded.road.xy;
    turnedNearPole.clear();
    std::vector<double> turned;  // own area x laid area: > 0 where a triangle keeps its turn
    std::size_t largest = 0;
    for (std::size_t k = 0; k < fan.own.size(); ++k) {
      const auto& t = fan.own[k];
      const double own = signedArea(v[t[0]].head<2>(), v[t[1]].head<2>(), v[t[2]].head<2>());
      const auto& g = unfolded.road.triangles[k];
      turned.push_back(own * signedArea(xy[g[0]], xy[g[1]], xy[g[2]]));
      if (std::abs(turned[k]) > std::abs(turned[largest])) largest = k;
    }
    for (std::size_t k = 0; k < turned.size(); ++k) {
      if (turned[k] * turned[largest] > 0) continue;
      const auto& t = fan.own[k];
      const auto& g = unfolded.road.triangles[k];
      const double own = signedArea(v[t[0]].head<2>(), v[t[1]].head<2>(), v[t[2]].head<2>());
      if (own == 0) continue;  // a cut's sliver of no area
      if (chart.hasPoleRows() && std::abs(turned[k]) <= 1e-18 * std::abs(turned[largest]))
        continue;  // (nor one of no area in the grid: a cut's along a meridian)
      if (chart.hasPoleRows()) {
        // Near one of lat-long's poles: halved until it turns no more (the overlay would see
        // the road cross itself there).
        if (k < mesh.triangles.size()) turnedNearPole.push_back(k);
        continue;
      }
      // How far it is turned over, in metres: its height in the grid, over its longest edge,
      // at the surface's scale along that edge.
      double depth = INFINITY;
      for (std::size_t e = 0; e < 3; ++e) {
        const std::uint32_t a = g[e], b = g[(e + 1) % 3];  // the first copy's: the mesh's own
        const double inGrid = (xy[a] - xy[b]).norm(), metres = (onSurface[a] - onSurface[b]).norm();
        if (inGrid > 0)
          depth = std::min(depth, 2 * std::abs(turned[k] / own) * metres / (inGrid * inGrid));
      }
      if (!(depth <= toleranceM))
        throw core::InputError(name + ": the road folds over where the " + chart.name() +
                               " bends under it; make it smaller or place it elsewhere");
    }
    return unfolded;
  };

  if (dynamic_cast<const core::OctahedralChart*>(&chart)) {
    // The octants' borders (the equator and the meridians at 0, 90, 180 and -90 degrees), where
    // the chart's parallels turn a right angle: a straight grid edge across one strays by up to
    // half its length, so none crosses.
    const std::array<Eigen::Vector3d, 3> borders{Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                                 Eigen::Vector3d(0, 0, 1)};
    for (const Eigen::Vector3d& n : borders)
      cutRoadAlong(base.vertices, base.triangles,
                   [&](const Eigen::Vector3d& p) { return n.dot(frame.at(p)); });
    partAtFoldEnds(base, chart, m, frame);
  }
  UnfoldedRoad laid = lay(base);
  if (laid.pieces > 1 && poles.empty()) {
    // It crosses a glued side: cut along the sides' planes first, so that each edge that crossed
    // one meets it where the surface's path does (the grid's straight edge across an octahedral
    // fold bends, by kilometres), then laid again.
    for (const Eigen::Vector3d& n : gluedSidePlanes(chart, m))
      cutRoadAlong(base.vertices, base.triangles,
                   [&](const Eigen::Vector3d& p) { return n.dot(frame.at(p)); });
    laid = lay(base);
  }
  // The chart bends a straight grid line (more the nearer a pole): every edge that strays beyond
  // the tolerance is halved, and laid again, until none does. Halving edges, not triangles, keeps
  // the mesh conforming: both triangles of an edge see it halved.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
  for (const Eigen::Vector3d& p : base.vertices)
    lo = lo.cwiseMin(p.head<2>()), hi = hi.cwiseMax(p.head<2>());
  const double shortest = (hi - lo).norm() * 1e-5;
  int halved = 0;
  for (int round = 0; round < 40; ++round) {
    // Also the triangles near one of lat-long's poles to halve (io/road_poles.hpp).
    std::vector<std::array<double, 3>> strays = laid.edgeStrayM;
    const bool wide = markNearPoles(base, polePoints, poles, turnedNearPole, shortest, strays);
    if (!(laid.strayM > toleranceM) && !wide) break;
    if (base.triangles.size() > 60000) break;  // (the checks below say what is left)
    const std::size_t before = base.vertices.size();
    halveStrayingEdges(base, strays, toleranceM, shortest, poles);
    if (base.vertices.size() == before) break;  // what strays is shorter than the floor
    halved += int(base.vertices.size() - before);
    laid = lay(base);
  }
  if (!turnedNearPole.empty())
    throw core::InputError(name + ": the road turns over in the " + chart.name() +
                           " chart's grid near its pole, where the grid's columns meet; place "
                           "it a little further from the pole or across it");
  return {std::move(laid.road), laid.pieces, laid.strayM, halved, !poles.empty()};
}

}  // namespace ps::io
