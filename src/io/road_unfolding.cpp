#include "io/road_unfolding.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <utility>

#include "core/input_error.hpp"

namespace ps::io {

std::vector<PlaneMove> gluingMoves(const core::Chart& chart, double m, int depth) {
  const core::Gluing g = chart.gluing();
  std::vector<PlaneMove> sides;
  if (g.uSides == core::SideGluing::kSeam)
    sides.push_back({1, {m, 0}}), sides.push_back({1, {-m, 0}});
  if (g.vSides == core::SideGluing::kSeam)
    sides.push_back({1, {0, m}}), sides.push_back({1, {0, -m}});
  // A fold's half turn about its side's midpoint: x -> 2c - x.
  if (g.uSides == core::SideGluing::kMirror)
    sides.push_back({-1, {0, m}}), sides.push_back({-1, {2 * m, m}});
  if (g.vSides == core::SideGluing::kMirror)
    sides.push_back({-1, {m, 0}}), sides.push_back({-1, {m, 2 * m}});
  std::vector<PlaneMove> moves{PlaneMove{}};
  std::vector<PlaneMove> last = moves;
  for (int d = 0; d < depth; ++d) {
    std::vector<PlaneMove> grown;
    for (const PlaneMove& a : sides)
      for (const PlaneMove& b : last) {
        const PlaneMove ab{a.s * b.s, a.s * b.t + a.t};  // a after b; t is a multiple of m: exact
        if (std::find(moves.begin(), moves.end(), ab) == moves.end())
          moves.push_back(ab), grown.push_back(ab);
      }
    last = grown;
  }
  return moves;
}

Eigen::Vector2d intoGrid(const core::Chart& chart, double m, Eigen::Vector2d p, bool clampOpen) {
  const core::Gluing g = chart.gluing();
  for (int k = 0; k < 8; ++k) {
    if (p.x() < 0 || p.x() > m) {
      const bool low = p.x() < 0;
      if (g.uSides == core::SideGluing::kSeam)
        p.x() += low ? m : -m;
      else if (g.uSides == core::SideGluing::kMirror)
        p = {low ? -p.x() : 2 * m - p.x(), m - p.y()};
      else if (clampOpen)
        p.x() = std::clamp(p.x(), 0.0, m);
      else
        break;
    } else if (p.y() < 0 || p.y() > m) {
      const bool low = p.y() < 0;
      if (g.vSides == core::SideGluing::kSeam)
        p.y() += low ? m : -m;
      else if (g.vSides == core::SideGluing::kMirror)
        p = {m - p.x(), low ? -p.y() : 2 * m - p.y()};
      else if (clampOpen)
        p.y() = std::clamp(p.y(), 0.0, m);
      else
        break;
    } else {
      break;
    }
  }
  if (!clampOpen) return p;
  return {std::clamp(p.x(), 0.0, m), std::clamp(p.y(), 0.0, m)};
}

std::vector<Eigen::Vector3d> gluedSidePlanes(const core::Chart& chart, double m) {
  const core::Gluing g = chart.gluing();
  const auto glued = [](core::SideGluing s) {
    return s == core::SideGluing::kSeam || s == core::SideGluing::kMirror;
  };
  std::vector<Eigen::Vector3d> planes;
  const auto side = [&](const auto& at) {  // at(t): the side's point at t in [0, 1]
    const Eigen::Vector3d a = at(0.25), b = at(0.5), c = at(0.75);
    Eigen::Vector3d n = a.cross(b);
    if (!(n.norm() > 1e-9 * a.norm() * b.norm())) n = b.cross(c);
    n.normalize();
    if (!(std::abs(n.dot(a)) + std::abs(n.dot(b)) + std::abs(n.dot(c)) < 1e-9 * a.norm()))
      return;  // not a great circle
    for (const Eigen::Vector3d& q : planes)
      if (std::abs(std::abs(q.dot(n)) - 1) < 1e-12) return;
    planes.push_back(n);
  };
  for (const double u : {0.0, m})
    if (glued(g.uSides)) side([&](double t) { return chart.positionAt(u, t * m, 0.0); });
  for (const double v : {0.0, m})
    if (glued(g.vSides)) side([&](double t) { return chart.positionAt(t * m, v, 0.0); });
  return planes;
}

void cutRoadAlong(std::vector<Eigen::Vector3d>& vertices,
                  std::vector<std::array<std::uint32_t, 3>>& triangles,
                  const std::function<double(const Eigen::Vector3d&)>& f) {
  // A vertex within rounding of the line is on it (a cut there would make a sliver).
  double scale = 0;
  for (const Eigen::Vector3d& p : vertices) scale = std::max(scale, std::abs(f(p)));
  std::vector<double> side;
  for (const Eigen::Vector3d& p : vertices)
    side.push_back(std::abs(f(p)) <= 1e-9 * scale ? 0.0 : f(p));
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> cut;
  const auto cutPoint = [&](std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);  // one computation for both triangles of the edge
    const auto [it, fresh] = cut.emplace(std::pair(a, b), std::uint32_t(vertices.size()));
    if (fresh) {
      const double t = side[a] / (side[a] - side[b]);
      const Eigen::Vector3d p = vertices[a] + t * (vertices[b] - vertices[a]);
      vertices.push_back(p);  // (evaluated first: the push may move the vertices)
      side.push_back(0.0);
    }
    return it->second;
  };
  std::vector<std::array<std::uint32_t, 3>> out;
  for (const auto& t : triangles) {
    const bool up = side[t[0]] >= 0 && side[t[1]] >= 0 && side[t[2]] >= 0;
    const bool down = side[t[0]] <= 0 && side[t[1]] <= 0 && side[t[2]] <= 0;
    if (up || down) {  // on one side (or touching the line)
      out.push_back(t);
      continue;
    }
    std::vector<std::uint32_t> above, below;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      if (side[a] >= 0) above.push_back(a);
      if (side[a] <= 0) below.push_back(a);
      if ((side[a] > 0 && side[b] < 0) || (side[a] < 0 && side[b] > 0)) {
        const std::uint32_t c = cutPoint(a, b);
        above.push_back(c), below.push_back(c);
      }
    }
    for (const auto* piece : {&above, &below})
      for (std::size_t k = 1; k + 1 < piece->size(); ++k)
        out.push_back({(*piece)[0], (*piece)[k], (*piece)[k + 1]});
  }
  triangles = std::move(out);
}

UnfoldedRoad unfoldRoad(
    const tin::Road& road, const std::vector<Eigen::Vector3d>& onSurface,
    const std::function<Eigen::Vector3d(std::uint32_t, std::uint32_t)>& midpoint,
    const core::Chart& chart, double m, const std::string& name, bool unfoldedAlready) {
  const std::vector<PlaneMove> moves = gluingMoves(chart, m);
  const std::size_t n = road.xy.size();
  std::vector<std::vector<std::uint32_t>> next(n);
  for (const auto& t : road.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      next[a].push_back(b), next[b].push_back(a);
    }
  // How far the grid's midpoint of an edge's ends A and B (in the plane around the grid), put on
  // the surface, lies from the edge's own midpoint.
  const auto miss = [&](std::uint32_t a, const Eigen::Vector2d& A, std::uint32_t b,
                        const Eigen::Vector2d& B) {
    const Eigen::Vector3d own = midpoint(a, b);
    // (Beyond an open side the chart's formula goes on: a cylinder's road past its rim, clipped
    // later, is judged as if the tube did.)
    const Eigen::Vector2d mid = intoGrid(chart, m, 0.5 * (A + B), false);
    return (chart.positionAt(mid.x(), mid.y(), 0.0) - own).norm();
  };

  // An edge's length on the surface, at least a millionth of the radius: an edge of no length
  // (between two copies of lat-long's pole) is continued by every image alike, within rounding.
  const auto edgeScale = [&](std::uint32_t a, std::uint32_t b) {
    return std::max((onSurface[a] - onSurface[b]).norm(), 1e-6 * onSurface[a].norm());
  };
  // A vertex at the end of a fold, which a half turn keeps in place, continues an edge alike in
  // the images on both sides of the fold: the edges from it say nothing of which, so the
  // unfolding does not go on from there (io/road_placement.hpp parts a road there in two halves
  // that meet across the fold).
  const auto foldEnd = [&](std::uint32_t a) {
    for (const PlaneMove& move : moves)
      if (!(move == PlaneMove{}) && (move(road.xy[a]) - road.xy[a]).norm() <= 1e-9 * m) return true;
    return false;
  };
  // Unfolded: breadth first from a vertex of each piece (not a fold's end while another is
  // left), every next vertex at the image of its grid point that continues the edge it is
  // reached by.
  std::vector<Eigen::Vector2d> unfolded(n);
  std::vector<char> placed(n, 0);
  if (unfoldedAlready) unfolded = road.xy, placed.assign(n, 1);
  for (std::size_t k = 0; k < 2 * n; ++k) {
    const std::size_t start = k % n;
    if (placed[start] || (k < n && foldEnd(std::uint32_t(start)))) continue;
    placed[start] = 1;
    unfolded[start] = road.xy[start];
    std::vector<std::uint32_t> queue{std::uint32_t(start)};
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::uint32_t a = queue[q];
      if (q > 0 && foldEnd(a)) continue;
      for (const std::uint32_t b : next[a]) {
        if (placed[b]) continue;
        // The images that continue the edge best, within a tenth of it (images a translation of
        // the grid's gluing apart move the midpoint by a gluing too, so they continue it alike),
        // and of those the nearest.
        const double chord = edgeScale(a, b);
        std::vector<std::pair<double, Eigen::Vector2d>> images;
        double best = INFINITY;
        for (const PlaneMove& move : moves) {
          const Eigen::Vector2d B = move(road.xy[b]);
          images.emplace_back(miss(a, unfolded[a], b, B), B);
          best = std::min(best, images.back().first);
        }
        double nearest = INFINITY;
        for (const auto& [e, B] : images)
          if (e <= best + 0.1 * chord && (B - unfolded[a]).norm() < nearest)
            nearest = (B - unfolded[a]).norm(), unfolded[b] = B;
        placed[b] = 1;
        queue.push_back(b);
      }
    }
  }

  // One piece: no edge would be continued better by moving an end across a side. (Round an end
  // of a fold the sphere's full turn is the grid's half turn: a road that io/road_placement did
  // not part there cannot be; nor one that reaches round a tube.)
  UnfoldedRoad out;
  for (const auto& t : road.triangles) {
    std::array<double, 3>& strays = out.edgeStrayM.emplace_back();
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      const double straight = miss(a, unfolded[a], b, unfolded[b]);
      strays[std::size_t(k)] = straight;
      out.strayM = std::max(out.strayM, straight);
      if (unfoldedAlready || !(straight > 0.05 * edgeScale(a, b))) continue;
      double across = INFINITY;
      for (const PlaneMove& move : moves)
        if (!(move == PlaneMove{}))
          across = std::min(across, miss(a, unfolded[a], b, move(unfolded[b])));
      if (!(across < 0.5 * straight)) continue;
      const Eigen::Vector3d own = midpoint(a, b).normalized();
      const double deg = 180.0 / std::numbers::pi;
      if (!(chart.sphereRadius() > 0))
        throw core::InputError(name + ": the road reaches too far round the " + chart.name() +
                               " to be laid in one piece; make it smaller");
      throw core::InputError(
          name + ": the road wraps around the end of a fold of the " + chart.name() +
          " chart near latitude " +
          core::exactNumber(std::round(std::asin(std::clamp(own.z(), -1.0, 1.0)) * deg * 100) /
                            100) +
          ", longitude " +
          core::exactNumber(std::round(std::atan2(own.y(), own.x()) * deg * 100) / 100) +
          " (the grid turns half round there where the sphere turns whole): place it elsewhere");
    }
  }

  // Each gluing that brings some of the unfolded road into the grid: a copy (clipped later).
  for (const PlaneMove& move : moves) {
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
    for (const Eigen::Vector2d& p : unfolded) {
      lo = lo.cwiseMin(move(p));
      hi = hi.cwiseMax(move(p));
    }
    if (hi.x() < 0 || lo.x() > m || hi.y() < 0 || lo.y() > m) continue;
    const std::uint32_t offset = std::uint32_t(out.road.xy.size());
    for (std::size_t v = 0; v < n; ++v) {
      const Eigen::Vector2d p = move(unfolded[v]);
      out.road.xy.push_back((p - road.xy[v]).norm() <= 1e-9 * m ? road.xy[v] : p);
      out.road.h.push_back(road.h[v]);
    }
    for (const auto& t : road.triangles)
      out.road.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    ++out.pieces;
  }
  return out;
}

}  // namespace ps::io
