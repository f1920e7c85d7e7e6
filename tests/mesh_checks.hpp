#pragma once
// Invariant checks shared by the tessellator, edit and stress tests.
#include <map>
#include <string>
#include <utility>

#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::testkit {

// Every edge of the mesh is shared by exactly two triangles with opposite orientation, after
// identifying seam twins and collapsing each pole row to one vertex (degenerate pole triangles
// are dropped). Returns "" when conforming, else a description of the first defect.
inline std::string conformityDefect(const terrain::Terrain& t, const terrain::Mesh& mesh) {
  const auto g = t.grid();
  const auto side = std::uint64_t(g.side());
  const int m = g.m();
  // One id per surface point, as the chart glues its grid (seam, pole rows, folded sides).
  auto id = [&](std::uint64_t gi) -> std::int64_t {
    const core::GridPoint p = t.chart().canonical(int(gi % side), int(gi / side));
    if (t.chart().hasPoleRows() && p.v == 0) return -1;
    if (t.chart().hasPoleRows() && p.v == m) return -2;
    return std::int64_t(p.v) * std::int64_t(side) + p.u;
  };
  std::map<std::pair<std::int64_t, std::int64_t>, int> directed;
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    const std::int64_t a = id(mesh.gridIndex[mesh.indices[3 * k]]),
                       b = id(mesh.gridIndex[mesh.indices[3 * k + 1]]),
                       c = id(mesh.gridIndex[mesh.indices[3 * k + 2]]);
    if (a == b || b == c || a == c) continue;
    for (auto e : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      if (++directed[e] > 1) return "directed edge used twice (flipped or overlapping triangles)";
    }
  }
  for (const auto& [e, n] : directed) {
    if (!directed.count({e.second, e.first})) {
      auto name = [&](std::int64_t x) {
        return x < 0 ? std::string(x == -1 ? "south pole" : "north pole")
                     : "(" + std::to_string(x % std::int64_t(side)) + "," +
                           std::to_string(x / std::int64_t(side)) + ")";
      };
      return "edge " + name(e.first) + "-" + name(e.second) +
             " has no partner: a crack or T-junction";
    }
  }
  return "";
}

}  // namespace ps::testkit
