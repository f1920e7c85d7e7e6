#include "tin/plane_stitch.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/input_error.hpp"
#include "tin/cdt.hpp"
#include "tin/road_checks.hpp"
#include "tin/tin_locator.hpp"
#include "tin/triangle_error.hpp"

namespace ps::tin {

namespace {

// Whether the segment ab meets the closed square [-half, half]^2 (Liang-Barsky).
bool segmentMeetsSquare(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half) {
  double t0 = 0, t1 = 1;
  const Eigen::Vector2d d = b - a;
  for (int axis = 0; axis < 2; ++axis)
    for (const double side : {-1.0, 1.0}) {
      // side * (a + t d)[axis] <= half
      const double p = side * d[axis], q = half - side * a[axis];
      if (p == 0) {
        if (q < 0) return false;
      } else if (p > 0) {
        t1 = std::min(t1, q / p);
      } else {
        t0 = std::max(t0, q / p);
      }
    }
  return t0 <= t1;
}

// Which surface triangles are meshed again: those facing the centre whose projection's bounding
// box meets the square about the road (so that they cover it), checked to keep one orientation
// and to leave no border edge in it.
struct PlaneRegion {
  std::vector<std::uint32_t> triangles;  // surface triangle indices
  double orientation = 1;                // +1: the surface's triangles run counter-clockwise
};

PlaneRegion planeRegion(const SurfaceMesh& surface, const std::vector<Eigen::Vector2d>& seen,
                        const std::vector<char>& facing, double box, double roadHalf) {
  PlaneRegion region;
  double areaSum = 0;
  for (std::uint32_t t = 0; t < surface.triangles.size(); ++t) {
    const auto& tri = surface.triangles[t];
    if (!(facing[tri[0]] && facing[tri[1]] && facing[tri[2]])) continue;
    Eigen::Vector2d lo = seen[tri[0]], hi = seen[tri[0]];
    for (const auto v : tri) lo = lo.cwiseMin(seen[v]), hi = hi.cwiseMax(seen[v]);
    if (lo.x() > box || lo.y() > box || hi.x() < -box || hi.y() < -box) continue;
    region.triangles.push_back(t);
    areaSum += signedArea(seen[tri[0]], seen[tri[1]], seen[tri[2]]);
  }
  if (region.triangles.empty())
    throw SurfaceUnseenInPlane(
        "no triangle of the surface about the road faces its plane within 60 degrees");
  region.orientation = areaSum >= 0 ? 1.0 : -1.0;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const std::uint32_t t : region.triangles) {
    const auto& tri = surface.triangles[t];
    if (!(region.orientation * signedArea(seen[tri[0]], seen[tri[1]], seen[tri[2]]) > 0))
      throw SurfaceUnseenInPlane(
          "the surface folds over about the road as seen from the planet's centre (a triangle "
          "there is seen edge-on or from behind): it cannot be stitched in the road's plane");
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[std::size_t(k)], b = tri[std::size_t((k + 1) % 3)];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  // Every point of the road's square covered once: no border edge of the region meets it.
  for (const auto& [edge, count] : uses)
    if (count == 1 && segmentMeetsSquare(seen[edge.first], seen[edge.second], roadHalf))
      throw SurfaceUnseenInPlane(
          "the surface's triangles about the road reach too far round the planet to be seen in "
          "the road's plane (a TIN this coarse: a smaller --error)");
  return region;
}

// The point on the plane of triangle abc (relative to the centre) along the ray through d.
Eigen::Vector3d alongRayOnto(const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  return d * (n.dot(a) / n.dot(d));
}

// Each surface vertex as seen in the plane from the centre, where it faces it within 60 degrees.
struct SeenInPlane {
  std::vector<Eigen::Vector2d> at;
  std::vector<char> facing;
};

SeenInPlane seenFromCentre(const SurfaceMesh& surface, const RoadPlane& plane) {
  const Eigen::Vector3d toOrigin = plane.origin - plane.centre;
  const double reach = toOrigin.dot(plane.up);
  SeenInPlane seen{std::vector<Eigen::Vector2d>(surface.positions.size(), Eigen::Vector2d::Zero()),
                   std::vector<char>(surface.positions.size(), 0)};
  for (std::size_t v = 0; v < surface.positions.size(); ++v) {
    const Eigen::Vector3d d = surface.positions[v] - plane.centre;
    const double w = d.dot(plane.up);
    if (!(w > 0.5 * d.norm())) continue;
    const Eigen::Vector3d s = d * (reach / w) - toOrigin;
    seen.at[v] = {s.dot(plane.x), s.dot(plane.y)};
    seen.facing[v] = 1;
  }
  return seen;
}

// The region's triangles with their own vertex numbers, shifted by `lo` so that every coordinate
// the locators see is >= 0.
struct LocalRegion {
  Eigen::Vector2d lo;
  double extent = 0;
  std::vector<Eigen::Vector2d> xy;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::map<std::uint32_t, std::uint32_t> local;  // surface vertex -> xy index
};

LocalRegion localRegion(const SurfaceMesh& surface, const std::vector<Eigen::Vector2d>& seen,
                        const PlaneRegion& region, double box) {
  LocalRegion r;
  r.lo = Eigen::Vector2d::Constant(-box);
  Eigen::Vector2d hi = Eigen::Vector2d::Constant(box);
  for (const std::uint32_t t : region.triangles)
    for (const auto v : surface.triangles[t])
      r.lo = r.lo.cwiseMin(seen[v]), hi = hi.cwiseMax(seen[v]);
  r.extent = (hi - r.lo).maxCoeff();
  for (const std::uint32_t t : region.triangles) {
    std::array<std::uint32_t, 3> lt{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = surface.triangles[t][std::size_t(k)];
      const auto [it, fresh] = r.local.emplace(v, std::uint32_t(r.xy.size()));
      if (fresh) r.xy.push_back(seen[v] - r.lo);
      lt[std::size_t(k)] = it->second;
    }
    r.triangles.push_back(lt);
  }
  return r;
}

// One triangulation: every region edge, then the road's, crossings made where they meet. A
// surface vertex carries its number and height 0; an added one keeps NaN. Returns the distinct
// vertices the road added.
std::size_t triangulateInPlane(Cdt& cdt, const LocalRegion& region,
                               const std::vector<Eigen::Vector2d>& road,
                               const std::vector<std::array<std::uint32_t, 3>>& roadTriangles) {
  std::vector<VertexHandle> regionVertex(region.xy.size());
  for (const auto& [v, k] : region.local) {
    regionVertex[k] = cdt.insert(Point(region.xy[k].x(), region.xy[k].y()));
    regionVertex[k]->info().index = v;
    regionVertex[k]->info().height = 0;
  }
  if (cdt.number_of_vertices() != region.local.size())
    throw SurfaceUnseenInPlane(
        "two of the surface's vertices about the road lie on one ray from the planet's centre: "
        "it cannot be stitched in the road's plane");
  for (const auto& [a, b] : edgesOf(region.triangles))
    cdt.insert_constraint(regionVertex[a], regionVertex[b]);
  std::size_t added = 0;
  std::vector<VertexHandle> roadVertex;
  for (const Eigen::Vector2d& p : road) {
    const VertexHandle h = cdt.insert(Point(p.x(), p.y()));
    if (std::isnan(h->info().height) && h->info().index == 0) {
      h->info().index = 1;  // counted once, however many road vertices share it
      ++added;
    }
    roadVertex.push_back(h);
  }
  for (const auto& [a, b] : edgesOf(roadTriangles))
    if (roadVertex[a] != roadVertex[b]) cdt.insert_constraint(roadVertex[a], roadVertex[b]);
  return added;
}

// Whether the region triangle t holds a, b and c (closed, within rounding).
bool holdsCorners(const LocalRegion& region, const std::array<std::uint32_t, 3>& t,
                  const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d &p = region.xy[t[0]], &q = region.xy[t[1]], &r = region.xy[t[2]];
  const double whole = signedArea(p, q, r);
  for (const Eigen::Vector2d* x : {&a, &b, &c})
    if (signedArea(*x, q, r) / whole < -1e-9 || signedArea(p, *x, r) / whole < -1e-9 ||
        signedArea(p, q, *x) / whole < -1e-9)
      return false;
  return true;
}

double areaOf(const std::vector<Eigen::Vector2d>& xy,
              const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  double sum = 0;
  for (const auto& t : triangles) sum += std::abs(signedArea(xy[t[0]], xy[t[1]], xy[t[2]]));
  return sum;
}

}  // namespace

PlaneStitch stitchInPlane(const SurfaceMesh& surface, const RoadPlane& plane,
                          const std::vector<Eigen::Vector2d>& roadXY,
                          const std::vector<std::array<std::uint32_t, 3>>& roadTriangles) {
  const Eigen::Vector3d toOrigin = plane.origin - plane.centre;
  const double reach = toOrigin.dot(plane.up);
  if (!(reach > 0)) throw std::logic_error("stitchInPlane: the plane passes through its centre");
  refuseDegenerateTriangles(Road{roadXY, std::vector<double>(roadXY.size(), 0.0), roadTriangles});
  double roadHalf = 0;
  for (const Eigen::Vector2d& p : roadXY) roadHalf = std::max(roadHalf, p.cwiseAbs().maxCoeff());
  if (std::atan(roadHalf * std::numbers::sqrt2 / reach) > std::numbers::pi / 4)
    throw core::InputError(
        "the road reaches more than 45 degrees from its place, too far to be stitched in its "
        "plane");
  const double box = 1.25 * roadHalf;
  const SeenInPlane seen = seenFromCentre(surface, plane);
  const PlaneRegion region = planeRegion(surface, seen.at, seen.facing, box, roadHalf);
  const LocalRegion local = localRegion(surface, seen.at, region, box);
  const double bucket = local.extent / 256;
  std::vector<Eigen::Vector2d> road;
  for (const Eigen::Vector2d& p : roadXY) road.push_back(p - local.lo);
  const TinLocator footprint(road, roadTriangles, local.extent, local.extent, bucket);
  refuseSelfIntersection(Road{road, std::vector<double>(road.size(), 0.0), roadTriangles},
                         footprint, "m^2 (in its plane)");
  const TinLocator onRegion(local.xy, local.triangles, local.extent, local.extent, bucket);
  Cdt cdt;
  PlaneStitch out;
  out.roadVertices = triangulateInPlane(cdt, local, road, roadTriangles);

  // The surface's triangles outside the region as they were; the faces, each in one region
  // triangle or outside the region (dropped), with each added vertex lifted along its ray.
  out.mesh.positions = surface.positions;
  std::vector<char> remeshed(surface.triangles.size(), 0);
  for (const std::uint32_t t : region.triangles) remeshed[t] = 1;
  out.regionTriangles = region.triangles.size();
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    if (!remeshed[t]) out.mesh.triangles.push_back(surface.triangles[t]), out.onRoad.push_back(0);
  std::map<VertexHandle, std::uint32_t> added;
  double keptArea = 0, keptRoadArea = 0;
  const auto flat = [](VertexHandle v) { return Eigen::Vector2d(v->point().x(), v->point().y()); };
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    const Eigen::Vector2d a = flat(f->vertex(0)), b = flat(f->vertex(1)), c = flat(f->vertex(2));
    const Eigen::Vector2d centroid = (a + b + c) / 3.0;
    // Its host holds all three corners (a face outside the region, a sliver along its border,
    // may have its centroid on a region triangle's edge, but not its far corner).
    std::optional<TinLocator::Hit> host;
    double best = -INFINITY;
    onRegion.visit(centroid, [&](const TinLocator::Hit& hit) {
      const double inside = std::min({hit.l0, hit.l1, hit.l2});
      if (inside > best && holdsCorners(local, local.triangles[hit.triangle], a, b, c))
        best = inside, host = hit;
    });
    if (!host) continue;
    const auto& terrain = surface.triangles[region.triangles[host->triangle]];
    const Eigen::Vector3d ta = surface.positions[terrain[0]] - plane.centre;
    const Eigen::Vector3d tb = surface.positions[terrain[1]] - plane.centre;
    const Eigen::Vector3d tc = surface.positions[terrain[2]] - plane.centre;
    std::array<std::uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const VertexHandle v = f->vertex(k);
      if (!std::isnan(v->info().height)) {
        tri[std::size_t(k)] = v->info().index;
        continue;
      }
      auto it = added.find(v);
      if (it == added.end()) {
        const Eigen::Vector2d q = flat(v) + local.lo;
        const Eigen::Vector3d ray = toOrigin + q.x() * plane.x + q.y() * plane.y;
        out.mesh.positions.push_back(plane.centre + alongRayOnto(ray, ta, tb, tc));
        it = added.emplace(v, std::uint32_t(out.mesh.positions.size() - 1)).first;
      }
      tri[std::size_t(k)] = it->second;
      out.addedVertexErrorM = std::max(
          out.addedVertexErrorM,
          pointTriangleDistance(out.mesh.positions[it->second], surface.positions[terrain[0]],
                                surface.positions[terrain[1]], surface.positions[terrain[2]]));
    }
    if (region.orientation < 0) std::swap(tri[1], tri[2]);
    const double area = std::abs(signedArea(a, b, c));
    const bool onRoad = footprint.contains(centroid, 0.0);
    keptArea += area;
    keptRoadArea += onRoad ? area : 0.0;
    out.mesh.triangles.push_back(tri);
    out.onRoad.push_back(onRoad ? 1 : 0);
  }
  out.crossingVertices = added.size() - std::min(added.size(), out.roadVertices);
  // The faces must tile the region and the road exactly (up to rounding): the projection is one
  // to one there (checked above), so a gap or an overlap would be this code's mistake.
  const double regionArea = areaOf(local.xy, local.triangles),
               roadArea = areaOf(road, roadTriangles);
  if (std::abs(keptArea - regionArea) > 1e-9 * regionArea ||
      std::abs(keptRoadArea - roadArea) > 1e-9 * regionArea)
    throw std::logic_error("stitchInPlane: the faces cover " + core::exactNumber(keptArea) +
                           " of the region's " + core::exactNumber(regionArea) + " and " +
                           core::exactNumber(keptRoadArea) + " of the road's " +
                           core::exactNumber(roadArea));
  return out;
}

}  // namespace ps::tin
