#include "io/road_poles.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <string>

#include "core/input_error.hpp"

namespace ps::io {

namespace {

double planeArea(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// Round a pole the grid is a strip whose ends the seam glues: a road that holds the pole is
// parted along one edge from it to a vertex on the road's border, which gets a twin in the
// triangles on one side of that edge, so that it lies in the strip once, without winding round
// (the unfolding then moves each part across the seam as it goes). A road with the pole on its
// border needs no parting (-1). Returns the vertex at the border end of the edge (its twin the
// last vertex), or nullopt where no edge from the pole reaches the border.
std::optional<std::int64_t> slitToBorder(RoadMesh& mesh, std::uint32_t pole) {
  using Edge = std::pair<std::uint32_t, std::uint32_t>;
  const auto key = [](std::uint32_t x, std::uint32_t y) {
    return Edge(std::min(x, y), std::max(x, y));
  };
  std::map<Edge, int> uses;
  for (const auto& t : mesh.triangles)
    for (std::size_t k = 0; k < 3; ++k) ++uses[key(t[k], t[(k + 1) % 3])];
  std::set<std::uint32_t> border;
  for (const auto& [e, n] : uses)
    if (n == 1) border.insert(e.first), border.insert(e.second);
  if (border.count(pole)) return -1;
  std::int64_t end = -1;  // the nearest neighbour on the border
  for (const auto& [e, n] : uses) {
    if (e.first != pole && e.second != pole) continue;
    const std::uint32_t a = e.first == pole ? e.second : e.first;
    if (!border.count(a)) continue;
    if (end < 0 || (mesh.vertices[a] - mesh.vertices[pole]).head<2>().norm() <
                       (mesh.vertices[std::size_t(end)] - mesh.vertices[pole]).head<2>().norm())
      end = a;
  }
  if (end < 0) return std::nullopt;
  const auto a = std::uint32_t(end);
  // The triangles round a, joined across their edges at a but the one to the pole: two groups,
  // one of them the side where the edge runs from the pole to a in the triangle's turn.
  std::vector<std::size_t> star;
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const auto& t = mesh.triangles[k];
    if (t[0] == a || t[1] == a || t[2] == a) star.push_back(k);
  }
  std::vector<int> group(star.size(), -1);
  std::size_t first = 0;
  for (std::size_t i = 0; i < star.size(); ++i) {
    const auto& t = mesh.triangles[star[i]];
    for (std::size_t k = 0; k < 3; ++k)
      if (t[k] == pole && t[(k + 1) % 3] == a) first = i;
  }
  const auto shares = [&](std::size_t i, std::size_t j) {
    for (const std::uint32_t x : mesh.triangles[star[i]])
      if (x != a && x != pole)
        for (const std::uint32_t y : mesh.triangles[star[j]])
          if (x == y) return true;
    return false;
  };
  group[first] = 0;
  for (std::vector<std::size_t> queue{first}; !queue.empty();) {
    const std::size_t i = queue.back();
    queue.pop_back();
    for (std::size_t j = 0; j < star.size(); ++j)
      if (group[j] < 0 && shares(i, j)) group[j] = 0, queue.push_back(j);
  }
  const auto twin = std::uint32_t(mesh.vertices.size());
  mesh.vertices.push_back(mesh.vertices[a]);
  for (std::size_t i = 0; i < star.size(); ++i)
    if (group[i] < 0)
      for (std::uint32_t& v : mesh.triangles[star[i]])
        if (v == a) v = twin;
  return end;
}

}  // namespace

// Lat-long's poles that face the road's plane: each one's point in the plane (through the
// sphere's centre) and its grid row.
std::vector<std::pair<Eigen::Vector2d, double>> polesInPlane(const core::Chart& chart, double m,
                                                             const RoadFrame& frame) {
  std::vector<std::pair<Eigen::Vector2d, double>> out;
  if (!chart.hasPoleRows()) return out;
  for (const double side : {-1.0, 1.0}) {
    const Eigen::Vector3d end(0, 0, side);
    if (!(end.dot(frame.up) > 0)) continue;
    const Eigen::Vector3d q = end * (frame.origin.dot(frame.up) / end.dot(frame.up));
    out.emplace_back(
        Eigen::Vector2d((q - frame.origin).dot(frame.x), (q - frame.origin).dot(frame.y)),
        side < 0 ? 0.0 : m);
  }
  return out;
}

// Where lat-long's pole lies in a road's footprint (or within `snap` of it) the grid has no point
// for it but a whole row, so the road gets a vertex there: a vertex within `snap` of it moved
// onto it, else each triangle that holds it, or has it within `snap` beyond an edge, split at
// it, and the road parted from it to its border (slitToBorder). Returns each pole's vertex and
// its grid row (0 or m), and in `slits` the parting's end (or -1); layRoadOnPlanet spreads the
// pole along its row (`spreadPoles`).
std::vector<std::pair<std::uint32_t, double>> insertPoles(RoadMesh& mesh, const core::Chart& chart,
                                                          double m, const RoadFrame& frame,
                                                          double snap,
                                                          std::vector<std::int64_t>& slits,
                                                          const std::string& name) {
  std::vector<std::pair<std::uint32_t, double>> poles;
  double extent = 0;
  for (const Eigen::Vector3d& p : mesh.vertices) extent = std::max(extent, p.head<2>().norm());
  const double tol = 1e-9 * std::max(extent, frame.origin.norm());
  for (const auto& [e, row] : polesInPlane(chart, m, frame)) {
    std::int64_t pole = -1;
    double nearest = snap;
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
      if ((mesh.vertices[v].head<2>() - e).norm() <= nearest)
        nearest = (mesh.vertices[v].head<2>() - e).norm(), pole = std::int64_t(v);
    if (pole >= 0) mesh.vertices[std::size_t(pole)].head<2>() = e;
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;  // each edge's triangles
    for (const auto& t : mesh.triangles)
      for (std::size_t k = 0; k < 3; ++k)
        ++uses[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
    std::vector<std::array<std::uint32_t, 3>> out;
    std::int64_t split = -1;
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector2d corner[3] = {mesh.vertices[t[0]].head<2>(),
                                         mesh.vertices[t[1]].head<2>(),
                                         mesh.vertices[t[2]].head<2>()};
      const double area = planeArea(corner[0], corner[1], corner[2]);
      const double bary[3] = {planeArea(e, corner[1], corner[2]) / area,
                              planeArea(corner[0], e, corner[2]) / area,
                              planeArea(corner[0], corner[1], e) / area};
      bool holds = area != 0 && pole < 0;
      for (int k = 0; k < 3 && holds; ++k) {
        // Inside, or within `snap` beyond edge k (between its ends).
        const double len = (corner[(k + 2) % 3] - corner[(k + 1) % 3]).norm();
        const double beyond = -bary[k] * 2 * std::abs(area) / len;
        holds = bary[k] >= 0 ||
                (beyond <= snap + tol && bary[(k + 1) % 3] > 0 && bary[(k + 2) % 3] > 0);
      }
      if (!holds) {
        out.push_back(t);
        continue;
      }
      if (split < 0) {  // the pole's vertex, made with the first triangle split at it
        split = std::int64_t(mesh.vertices.size());
        double z = 0;
        for (int k = 0; k < 3; ++k) z += bary[k] * mesh.vertices[t[std::size_t(k)]].z();
        mesh.vertices.emplace_back(e.x(), e.y(), z);
      }
      const auto p = std::uint32_t(split);
      for (std::size_t k = 0; k < 3; ++k) {
        std::array<std::uint32_t, 3> piece = t;
        piece[k] = p;
        // The piece along an inner edge the pole lies within `snap` of is left out: the triangle
        // across that edge is split at the pole too and covers it.
        const std::uint32_t x = t[(k + 1) % 3], y = t[(k + 2) % 3];
        const double len = (corner[(k + 2) % 3] - corner[(k + 1) % 3]).norm();
        if (std::abs(bary[k]) * 2 * std::abs(area) / len <= snap + tol &&
            uses[{std::min(x, y), std::max(x, y)}] == 2)
          continue;
        if (planeArea(mesh.vertices[piece[0]].head<2>(), mesh.vertices[piece[1]].head<2>(),
                      mesh.vertices[piece[2]].head<2>()) *
                (area > 0 ? 1 : -1) >
            tol * extent)
          out.push_back(piece);  // (a piece beyond an edge the pole lies past has no area)
      }
    }
    mesh.triangles = std::move(out);
    if (pole < 0) pole = split;
    if (pole < 0) continue;
    const std::optional<std::int64_t> slit = slitToBorder(mesh, std::uint32_t(pole));
    if (!slit)
      throw core::InputError(
          name +
          ": the road holds one of the lat-long chart's poles but no edge from it reaches the "
          "road's border (make the vertex nearest the pole a corner of its border)");
    poles.emplace_back(std::uint32_t(pole), row);
    slits.push_back(*slit);
  }
  return poles;
}

// The triangles near one of lat-long's poles (not round one) whose longest edge is above
// `widest` times their distance from it: the grid's straight edges bend from theirs by about
// d phi^2 / 8 (at a distance d, spanning an angle phi of the meridians, which are not affine in
// the grid), which turns a thin one over. Those longer than `shortest` are halved until none is.
std::vector<std::size_t> wideNearPoles(const RoadMesh& mesh,
                                       const std::vector<std::pair<Eigen::Vector2d, double>>& at,
                                       const std::vector<std::pair<std::uint32_t, double>>& poles,
                                       double shortest, double widest) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const auto& t = mesh.triangles[k];
    bool round = false;
    for (const auto& pole : poles)
      round |= t[0] == pole.first || t[1] == pole.first || t[2] == pole.first;
    if (round) continue;
    const Eigen::Vector2d c[3] = {mesh.vertices[t[0]].head<2>(), mesh.vertices[t[1]].head<2>(),
                                  mesh.vertices[t[2]].head<2>()};
    double longest = 0;
    for (int i = 0; i < 3; ++i) longest = std::max(longest, (c[(i + 1) % 3] - c[i]).norm());
    if (!(longest > shortest)) continue;
    for (const auto& [e, row] : at) {
      double d = INFINITY;  // from the pole to the triangle
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector2d p = c[i] - e, q = c[(i + 1) % 3] - e;
        const double s = std::clamp(-p.dot(q - p) / (q - p).squaredNorm(), 0.0, 1.0);
        d = std::min(d, (p + s * (q - p)).norm());
      }
      if (longest > widest * d) {
        out.push_back(k);
        break;
      }
    }
  }
  return out;
}

// A road parted from a pole to `end` (slitToBorder), laid round the pole in the plane around the
// grid without winding: each vertex's u the longitude of its point taken on from the parting's,
// through a full turn (in the road's plane the meridians are rays from the pole: its gnomonic
// projection keeps great circles straight), a vertex on the parting taken at the turn's start or
// end as its triangles lie. Then the unfolding continues every edge as it is.
void unwrapRoundPole(tin::Road& grid, const std::vector<Eigen::Vector3d>& onSurface,
                     const std::vector<std::array<std::uint32_t, 3>>& triangles, std::uint32_t end,
                     double m) {
  const double turn = 2 * std::numbers::pi;
  const auto lon = [&](const Eigen::Vector3d& p) { return std::atan2(p.y(), p.x()); };
  const double start = lon(onSurface[end]);
  const auto from = [&](const Eigen::Vector3d& p) {  // in [0, turn)
    const double d = std::fmod(lon(p) - start, turn);
    return d < 0 ? d + turn : d;
  };
  const double onParting = 1e-9;
  std::vector<double> d(grid.xy.size());
  for (std::size_t v = 0; v < d.size(); ++v) {
    d[v] = from(onSurface[v]);
    if (d[v] > turn - onParting) d[v] = 0;
  }
  // A vertex on the parting: at the turn's end where its triangles lie past half a turn.
  std::vector<double> side(d.size(), 0);
  for (const auto& t : triangles) {
    const Eigen::Vector3d centre = (onSurface[t[0]] + onSurface[t[1]] + onSurface[t[2]]) / 3;
    const double c = from(centre);
    for (const std::uint32_t v : t)
      if (d[v] < onParting && Eigen::Vector2d(onSurface[v].x(), onSurface[v].y()).norm() > 0)
        side[v] = c > 0.5 * turn ? turn : 0;
  }
  for (std::size_t v = 0; v < d.size(); ++v)
    if (d[v] < onParting) d[v] = side[v];
  // (on 2^-20 of a grid unit, so that the parting's two sides, u0 and u0 + m, meet exactly where
  // the unfolding's copies move the one onto the other)
  const double step = std::ldexp(1.0, 20);
  const double u0 = std::round((start + std::numbers::pi) * m / turn * step) / step;
  for (std::size_t v = 0; v < d.size(); ++v) grid.xy[v].x() = u0 + d[v] * m / turn;
}

// A pole's vertex spread along its grid row: in each triangle (P, a, b) round it, P becomes a copy
// under a (a's u on the pole's row), and a filler (P under a, b, P under b) with no area on the
// surface closes the grid's quad between the two meridians, so the grid's triangles cover the
// strip round the pole as the road's cover the disc. `own` holds each grid triangle's triangle of
// the road's plane (a filler's has no area), `origin` each grid vertex's vertex of that plane.

PoleFan spreadPoles(tin::Road& grid, std::vector<Eigen::Vector3d>& onSurface,
                    const std::vector<std::array<std::uint32_t, 3>>& triangles,
                    const std::vector<std::pair<std::uint32_t, double>>& poles) {
  PoleFan fan;
  fan.own = triangles;
  for (std::uint32_t v = 0; v < grid.xy.size(); ++v) fan.origin.push_back(v);
  fan.poleCopy.assign(grid.xy.size(), 0);
  for (const auto& entry : poles) {
    const std::uint32_t pole = entry.first;  // (not a structured binding: the lambda takes them)
    const double row = entry.second;
    std::map<std::uint32_t, std::uint32_t> under;  // a neighbour -> the pole's copy under it
    const auto copyUnder = [&](std::uint32_t a) {
      const auto [it, fresh] = under.emplace(a, std::uint32_t(grid.xy.size()));
      if (fresh) {
        grid.xy.emplace_back(grid.xy[a].x(), row);
        grid.h.push_back(grid.h[pole]);
        onSurface.push_back(onSurface[pole]);
        fan.origin.push_back(pole);
        fan.poleCopy.push_back(1);
      }
      return it->second;
    };
    for (std::size_t k = 0, n = triangles.size(); k < n; ++k) {
      const auto& t = triangles[k];
      for (std::size_t j = 0; j < 3; ++j) {
        if (t[j] != pole) continue;
        const std::uint32_t a = t[(j + 1) % 3], b = t[(j + 2) % 3];
        const std::uint32_t pa = copyUnder(a), pb = copyUnder(b);
        grid.triangles[k][j] = pa;
        grid.triangles.push_back({pa, b, pb});
        fan.own.push_back({pole, b, pole});
      }
    }
  }
  return fan;
}

void leavePoleEdgesUnjudged(UnfoldedRoad& unfolded, const tin::Road& grid, const PoleFan& fan) {
  unfolded.strayM = 0;
  for (std::size_t k = 0; k < grid.triangles.size(); ++k)
    for (std::size_t e = 0; e < 3; ++e) {
      double& stray = unfolded.edgeStrayM[k][e];
      if (fan.poleCopy[grid.triangles[k][e]] || fan.poleCopy[grid.triangles[k][(e + 1) % 3]])
        stray = 0;
      unfolded.strayM = std::max(unfolded.strayM, stray);
    }
}

bool markNearPoles(const RoadMesh& mesh, const std::vector<std::pair<Eigen::Vector2d, double>>& at,
                   const std::vector<std::pair<std::uint32_t, double>>& poles,
                   const std::vector<std::size_t>& turned, double shortest,
                   std::vector<std::array<double, 3>>& strays) {
  constexpr double kWidest = 1.0 / 8;  // a triangle's size over its distance from the pole
  std::vector<std::size_t> wide = wideNearPoles(mesh, at, poles, 2 * shortest, kWidest);
  // Where the grid still turns a triangle over: it and the triangles round its corners.
  std::set<std::uint32_t> near;
  for (const std::size_t k : turned)
    near.insert(mesh.triangles[k].begin(), mesh.triangles[k].end());
  for (const auto& pole : poles) near.erase(pole.first);
  for (std::size_t k = 0; k < mesh.triangles.size() && !near.empty(); ++k)
    for (const std::uint32_t v : mesh.triangles[k])
      if (near.count(v)) {
        wide.push_back(k);
        break;
      }
  for (const std::size_t k : wide)
    for (std::size_t e = 0; e < 3; ++e) {
      // (not an edge from a pole: a triangle round it is halved across from it)
      bool fromPole = false;
      for (const auto& pole : poles)
        fromPole |=
            mesh.triangles[k][e] == pole.first || mesh.triangles[k][(e + 1) % 3] == pole.first;
      if (!fromPole) strays[k][e] = INFINITY;
    }
  return !wide.empty();
}

}  // namespace ps::io
