#include "tin/overlay.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "core/input_error.hpp"
#include "tin/cdt.hpp"
#include "tin/greedy_inserter.hpp"
#include "tin/road_checks.hpp"
#include "tin/road_drape.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_locator.hpp"
#include "tin/triangle_error.hpp"

namespace ps::tin {

namespace {

struct PolyVertex {
  Eigen::Vector2d p;
  double h;
};

// Sutherland-Hodgman: the polygon's part inside the half-plane sign * (p[axis] - bound) <= 0.
std::vector<PolyVertex> clipHalfPlane(const std::vector<PolyVertex>& in, int axis, double bound,
                                      double sign) {
  std::vector<PolyVertex> out;
  for (std::size_t k = 0; k < in.size(); ++k) {
    const PolyVertex& a = in[k];
    const PolyVertex& b = in[(k + 1) % in.size()];
    const double da = sign * (a.p[axis] - bound), db = sign * (b.p[axis] - bound);
    if (da <= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
      const double s = da / (da - db);
      PolyVertex c{a.p + s * (b.p - a.p), a.h + s * (b.h - a.h)};
      c.p[axis] = bound;  // exactly on the border, whatever the rounding
      out.push_back(c);
    }
  }
  return out;
}

// The road's part inside [0, xMax] x [0, yMax]: triangles wholly inside kept, the others cut
// (fan-triangulated) or dropped; vertices shared by exact coordinates.
Road clipRoad(const Road& in, double xMax, double yMax, std::size_t& clipped) {
  Road out;
  std::map<std::pair<double, double>, std::uint32_t> index;
  auto vertex = [&](const PolyVertex& v) {
    const auto [it, fresh] =
        index.emplace(std::pair(v.p.x(), v.p.y()), std::uint32_t(out.xy.size()));
    if (fresh) out.xy.push_back(v.p), out.h.push_back(v.h);
    return it->second;
  };
  for (const auto& t : in.triangles) {
    std::vector<PolyVertex> poly;
    for (const auto v : t) poly.push_back({in.xy[v], in.h[v]});
    const bool inside = std::all_of(poly.begin(), poly.end(), [&](const PolyVertex& v) {
      return v.p.x() >= 0 && v.p.x() <= xMax && v.p.y() >= 0 && v.p.y() <= yMax;
    });
    if (!inside) {
      ++clipped;
      poly = clipHalfPlane(poly, 0, 0.0, -1.0);
      poly = clipHalfPlane(poly, 0, xMax, 1.0);
      poly = clipHalfPlane(poly, 1, 0.0, -1.0);
      poly = clipHalfPlane(poly, 1, yMax, 1.0);
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
      if (std::abs(signedArea(poly[0].p, poly[k].p, poly[k + 1].p)) < 1e-12) continue;
      out.triangles.push_back({vertex(poly[0]), vertex(poly[k]), vertex(poly[k + 1])});
    }
  }
  return out;
}

// Whether a side of the grid is glued to one (a seam) or to itself (a fold).
bool isGluedSide(core::SideGluing s) {
  return s == core::SideGluing::kSeam || s == core::SideGluing::kMirror;
}

// A road cut at a glued side of a whole chart's grid has a vertex on each side of it, twins that
// the weld must key alike (tin_check's weldKey: a seam's y, a fold's min(x, m - x)), though each
// was cut from its own copy of the road with its own rounding. On 2^-20 of a lattice unit both are
// exact, their twin's coordinate too (m - x of two such numbers), and they agree: the roundings
// differ by ulps, far below half a step.
void snapGluedSideVertices(Road& road, const SampleField& field) {
  if (!field.wholeChart()) return;
  const core::Gluing g = field.chart->gluing();
  const double xMax = field.width - 1, yMax = field.height - 1, step = std::ldexp(1.0, 20);
  const auto snap = [&](double t) { return std::round(t * step) / step; };
  for (Eigen::Vector2d& p : road.xy) {
    if (isGluedSide(g.uSides) && (p.x() == 0 || p.x() == xMax)) p.y() = snap(p.y());
    if (isGluedSide(g.vSides) && (p.y() == 0 || p.y() == yMax)) p.x() = snap(p.x());
  }
  // Two vertices that the snap put on one point are one (and a triangle left with no area goes).
  std::map<std::pair<double, double>, std::uint32_t> at;
  std::vector<std::uint32_t> same(road.xy.size());
  for (std::uint32_t v = 0; v < road.xy.size(); ++v)
    same[v] = at.emplace(std::pair(road.xy[v].x(), road.xy[v].y()), v).first->second;
  std::vector<std::array<std::uint32_t, 3>> kept;
  for (auto t : road.triangles) {
    for (std::uint32_t& v : t) v = same[v];
    if (signedArea(road.xy[t[0]], road.xy[t[1]], road.xy[t[2]]) != 0) kept.push_back(t);
  }
  road.triangles = std::move(kept);
}

// Every vertex on a glued side of a whole chart's grid with its twins there too: a road piece
// that only touches a side (a vertex or an edge of it exactly on the side, the rest of the road
// on one side of it) puts vertices on that side alone, and the weld then finds no twin for them
// and leaves the surface open there. A twin inserted on the other side splits the terrain's
// border edge as the road's vertex splits it here; it takes the vertex's height where that is
// known (a stencil's own heights), else it sits on the terrain mesh as the vertex does.
void addGluedTwins(Cdt& cdt, const SampleField& field) {
  if (!field.wholeChart()) return;
  const core::Gluing g = field.chart->gluing();
  const double xMax = field.width - 1, yMax = field.height - 1;
  const auto twins = [&](const Eigen::Vector2d& p) {
    std::vector<Eigen::Vector2d> out;
    if (isGluedSide(g.uSides) && (p.x() == 0 || p.x() == xMax))
      out.push_back(g.uSides == core::SideGluing::kSeam ? Eigen::Vector2d(xMax - p.x(), p.y())
                                                        : Eigen::Vector2d(p.x(), yMax - p.y()));
    if (isGluedSide(g.vSides) && (p.y() == 0 || p.y() == yMax))
      out.push_back(g.vSides == core::SideGluing::kSeam ? Eigen::Vector2d(p.x(), yMax - p.y())
                                                        : Eigen::Vector2d(xMax - p.x(), p.y()));
    return out;
  };
  // Twice: a corner's twin across one side may need its twin across the other.
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::pair<Eigen::Vector2d, double>> wanted;
    for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
      const Eigen::Vector2d p(v->point().x(), v->point().y());
      for (const Eigen::Vector2d& q : twins(p))
        if (q != p) wanted.emplace_back(q, v->info().height);
    }
    for (const auto& [q, h] : wanted) {
      const VertexHandle t = cdt.insert(Point(q.x(), q.y()));
      if (std::isnan(t->info().height)) t->info().height = h;
    }
  }
}

// The road's vertices and edges into the triangulation, each edge a constraint (draped: a chain
// of constraints through the points where it crosses the terrain's edges). Its vertices carry
// its own heights where `ownHeights` (the stencil's road surface).
std::vector<VertexHandle> insertRoad(Cdt& cdt, const Road& road, const DrapedRoad* drape,
                                     bool ownHeights) {
  std::vector<VertexHandle> roadVertex(road.xy.size());
  for (std::size_t v = 0; v < road.xy.size(); ++v) {
    const Eigen::Vector2d& p = drape ? drape->vertex[v] : road.xy[v];
    roadVertex[v] = cdt.insert(Point(p.x(), p.y()));
    if (ownHeights) roadVertex[v]->info().height = road.h[v];
  }
  for (const auto& [a, b] : edgesOf(road.triangles)) {
    if (!drape) {
      cdt.insert_constraint(roadVertex[a], roadVertex[b]);
      continue;
    }
    const std::vector<Eigen::Vector2d> path = drape->path(a, b);
    VertexHandle from = roadVertex[a];
    for (std::size_t k = 1; k < path.size(); ++k) {
      const VertexHandle to =
          k + 1 == path.size() ? roadVertex[b] : cdt.insert(Point(path[k].x(), path[k].y()));
      if (to != from) cdt.insert_constraint(from, to);
      from = to;
    }
  }
  return roadVertex;
}

}  // namespace

OverlayResult overlayRoad(const SampleField& field, const Tin& terrain, const Road& roadIn,
                          OverlayMode mode) {
  field.validate("overlay");
  OverlayResult result;
  OverlayReport& rep = result.report;
  rep.terrainVertices = terrain.xy.size();
  rep.roadVertices = roadIn.xy.size();
  rep.roadTriangles = roadIn.triangles.size();
  const double xMax = field.width - 1, yMax = field.height - 1;
  refuseDegenerateTriangles(roadIn);
  Road road = clipRoad(roadIn, xMax, yMax, rep.clippedRoadTriangles);
  snapGluedSideVertices(road, field);
  if (road.triangles.empty()) throw core::InputError("the road lies wholly outside the terrain");
  const TinLocator footprint(road.xy, road.triangles, field.width, field.height);
  refuseSelfIntersection(road, footprint);
  const TinLocator onTerrain(terrain.xy, terrain.triangles, field.width, field.height);
  std::vector<Eigen::Vector3d> terrainCorner(terrain.xy.size());
  for (std::size_t v = 0; v < terrain.xy.size(); ++v)
    terrainCorner[v] = field.positionAt(terrain.xy[v].x(), terrain.xy[v].y(), terrain.h[v]);

  Cdt cdt;
  std::vector<VertexHandle> terrainVertex(terrain.xy.size());
  for (std::size_t v = 0; v < terrain.xy.size(); ++v) {
    terrainVertex[v] = cdt.insert(Point(terrain.xy[v].x(), terrain.xy[v].y()));
    terrainVertex[v]->info().height = terrain.h[v];
  }
  if (mode == OverlayMode::kStitch) {
    // Every terrain edge constrained: the triangulation is the terrain's, edge for edge.
    for (const auto& [a, b] : edgesOf(terrain.triangles))
      cdt.insert_constraint(terrainVertex[a], terrainVertex[b]);
  } else {
    for (std::size_t v = 0; v < terrain.xy.size(); ++v) {
      const Eigen::Vector2d& p = terrain.xy[v];
      const bool corner = (p.x() == 0 || p.x() == xMax) && (p.y() == 0 || p.y() == yMax);
      if (!corner && footprint.contains(p)) {
        cdt.remove(terrainVertex[v]);
        ++rep.removedTerrainVertices;
      }
    }
  }
  // On a planet a stitched road is draped over the mesh (tin/road_drape.hpp): its vertices
  // over their chart points, its edges along the mesh; elsewhere the grid is the ground's frame.
  std::optional<DrapedRoad> drape;
  if (mode == OverlayMode::kStitch && drapeable(field, terrain)) {
    drape = drapeRoad(field, terrain, terrainCorner, onTerrain, road);
    rep.drapedEdges = drape->drapedEdges;
    rep.undrapedEdges = drape->straightEdges;
    rep.drapeMoveM = drape->largestMoveM;
  }
  const std::vector<VertexHandle> roadVertex =
      insertRoad(cdt, road, drape ? &*drape : nullptr, mode == OverlayMode::kStencil);
  addGluedTwins(cdt, field);
  std::optional<DrapedFootprint> drapedFootprint;
  if (drape) drapedFootprint.emplace(*drape, road.triangles, field.width, field.height);

  std::vector<float> tolerance;
  if (mode == OverlayMode::kStencil) {
    // The ground outside the footprint, meshed again to the error; the footprint is the road's.
    const std::size_t before = cdt.number_of_vertices();
    tolerance.resize(field.heights.size());
    for (int j = 0; j < field.height; ++j)
      for (int i = 0; i < field.width; ++i) {
        const std::size_t k = field.index(i, j);
        tolerance[k] = footprint.contains({i, j}) ? 1e30f : float(field.tolerance(k));
      }
    SampleField refill = field;
    refill.perSampleTolerance = tolerance;
    GreedyInserter greedy(cdt, refill);
    greedy.measureAll();
    greedy.run();
    addGluedTwins(cdt, field);
    rep.refillVertices = cdt.number_of_vertices() - before;
  }

  // Vertices out: a stitch's added ones (road corners, crossings) sit on the terrain mesh.
  std::set<VertexHandle> fromRoad(roadVertex.begin(), roadVertex.end());
  std::uint32_t next = 0;
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
    v->info().index = next++;
    const Eigen::Vector2d p(v->point().x(), v->point().y());
    Eigen::Vector3d position;
    if (std::isnan(v->info().height)) {
      std::optional<TinLocator::Hit> host;
      onTerrain.visit(p, [&](const TinLocator::Hit& hit) {
        if (!host) host = hit;
      });
      if (!host) throw std::logic_error("overlay: a road vertex lies outside the terrain mesh");
      const auto& tri = terrain.triangles[host->triangle];
      v->info().height = host->l0 * terrain.h[tri[0]] + host->l1 * terrain.h[tri[1]] +
                         host->l2 * terrain.h[tri[2]];
      position = host->l0 * terrainCorner[tri[0]] + host->l1 * terrainCorner[tri[1]] +
                 host->l2 * terrainCorner[tri[2]];
      rep.addedVertexErrorM =
          std::max(rep.addedVertexErrorM,
                   pointTriangleDistance(position, terrainCorner[tri[0]], terrainCorner[tri[1]],
                                         terrainCorner[tri[2]]));
      if (!fromRoad.count(v)) ++rep.crossingVertices;
    } else {
      position = field.positionAt(p.x(), p.y(), v->info().height);
    }
    result.tin.xy.push_back(p);
    result.tin.h.push_back(v->info().height);
    result.positions.push_back(position);
  }
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    const std::array<std::uint32_t, 3> t = {f->vertex(0)->info().index, f->vertex(1)->info().index,
                                            f->vertex(2)->info().index};
    result.tin.triangles.push_back(t);
    const Eigen::Vector2d centroid =
        (result.tin.xy[t[0]] + result.tin.xy[t[1]] + result.tin.xy[t[2]]) / 3.0;
    const bool inside =
        drapedFootprint ? drapedFootprint->contains(centroid) : footprint.contains(centroid, 0.0);
    result.onRoad.push_back(inside ? 1 : 0);
  }

  if (mode == OverlayMode::kStencil) {
    // Inside the footprint: the road's surface against the result's, sample by sample.
    std::vector<Eigen::Vector3d> roadCorner(road.xy.size());
    for (std::size_t v = 0; v < road.xy.size(); ++v)
      roadCorner[v] = field.positionAt(road.xy[v].x(), road.xy[v].y(), road.h[v]);
    const TinLocator onResult(result.tin.xy, result.tin.triangles, field.width, field.height);
    for (int j = 0; j < field.height; ++j)
      for (int i = 0; i < field.width; ++i) {
        std::optional<TinLocator::Hit> inRoad;
        footprint.visit({i, j}, [&](const TinLocator::Hit& hit) {
          if (!inRoad) inRoad = hit;
        });
        if (!inRoad) continue;
        const auto& tt = road.triangles[inRoad->triangle];
        const Eigen::Vector3d q = inRoad->l0 * roadCorner[tt[0]] + inRoad->l1 * roadCorner[tt[1]] +
                                  inRoad->l2 * roadCorner[tt[2]];
        double best = INFINITY;
        onResult.visit({i, j}, [&](const TinLocator::Hit& hit) {
          const auto& rt = result.tin.triangles[hit.triangle];
          best = std::min(best,
                          pointTriangleDistance(q, result.positions[rt[0]], result.positions[rt[1]],
                                                result.positions[rt[2]]));
        });
        rep.footprintErrorM = std::max(rep.footprintErrorM, best);
      }
    SampleField outside = field;
    outside.perSampleTolerance = tolerance;
    rep.outsideErrorRatio = measureTinError(outside, result.tin, result.positions).maxRatio;
  }
  return result;
}

}  // namespace ps::tin
