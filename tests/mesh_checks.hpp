#pragma once
// Invariant checks shared by the tessellator, edit and stress tests.
#include <cmath>
#include <limits>
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

// Moller-Trumbore: where the ray o + t d meets the mesh's triangle at indices[first] (first a
// multiple of 3): t > 0, or infinity where it does not (o relative to the mesh's eye).
inline double rayMeetsTriangle(const terrain::Mesh& mesh, std::size_t first,
                               const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  constexpr double kMiss = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d a = mesh.positions[mesh.indices[first]].cast<double>();
  const Eigen::Vector3d e1 = mesh.positions[mesh.indices[first + 1]].cast<double>() - a;
  const Eigen::Vector3d e2 = mesh.positions[mesh.indices[first + 2]].cast<double>() - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-18) return kMiss;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) / det;
  if (u < 0 || u > 1) return kMiss;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0 || u + v > 1) return kMiss;
  const double t = e2.dot(q) / det;
  return t > 0 ? t : kMiss;
}

}  // namespace ps::testkit
