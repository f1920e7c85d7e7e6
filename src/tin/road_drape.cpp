#include "tin/road_drape.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_map>

#include "tin/overlay.hpp"

namespace ps::tin {

namespace {

// A crossing's fraction along a terrain edge, rounded to 2^-30: between lattice points under
// 2^22 apart the point then has an exact double, exactly on the edge.
constexpr double kFraction = 1073741824.0;
// A walk longer than this many steps has lost its way (a road edge crosses a few hundred
// terrain triangles at most).
constexpr int kMaxSteps = 1 << 20;

struct Adjacency {
  std::unordered_map<std::uint64_t, std::array<std::int64_t, 2>> edgeFaces;
  std::vector<std::vector<std::uint32_t>> vertexFaces;

  static std::uint64_t key(std::uint32_t a, std::uint32_t b) {
    return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
  }
  Adjacency(const Tin& t) : vertexFaces(t.xy.size()) {
    for (std::size_t f = 0; f < t.triangles.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t.triangles[f][std::size_t(k)],
                            b = t.triangles[f][std::size_t((k + 1) % 3)];
        auto [it, fresh] = edgeFaces.try_emplace(key(a, b), std::array<std::int64_t, 2>{-1, -1});
        it->second[it->second[0] < 0 ? 0 : 1] = std::int64_t(f);
        vertexFaces[a].push_back(std::uint32_t(f));
      }
  }
  std::int64_t across(std::uint32_t a, std::uint32_t b, std::size_t from) const {
    const auto it = edgeFaces.find(key(a, b));
    if (it == edgeFaces.end()) return -1;
    return it->second[0] == std::int64_t(from) ? it->second[1] : it->second[0];
  }
};

struct OnMesh {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // lattice
  Eigen::Vector3d at = Eigen::Vector3d::Zero();  // the mesh's point there
};

class Draper {
 public:
  Draper(const SampleField& field, const Tin& terrain, const std::vector<Eigen::Vector3d>& corner,
         const TinLocator& onTerrain)
      : field_(field), t_(terrain), corner_(corner), where_(onTerrain), adj_(terrain) {}

  Eigen::Vector3d up(const Eigen::Vector2d& p) const {
    return (field_.positionAt(p.x(), p.y(), 1.0) - field_.positionAt(p.x(), p.y(), 0.0))
        .normalized();
  }

  // The mesh's point at lattice point p (its host triangle's blend).
  std::optional<OnMesh> blendAt(const Eigen::Vector2d& p) const {
    std::optional<OnMesh> out;
    where_.visit(p, [&](const TinLocator::Hit& h) {
      if (out) return;
      const auto& tri = t_.triangles[h.triangle];
      out = OnMesh{p, h.l0 * corner_[tri[0]] + h.l1 * corner_[tri[1]] + h.l2 * corner_[tri[2]]};
    });
    return out;
  }

  // Where the line through p's chart point along the surface's normal there meets the mesh:
  // the host triangle's plane met, the meeting point's own lattice point taken, until it lies
  // in the triangle it was found by.
  std::optional<OnMesh> normalOntoMesh(const Eigen::Vector2d& p) const {
    const Eigen::Vector3d x = field_.positionAt(p.x(), p.y(), field_.heightAt(p.x(), p.y()));
    const Eigen::Vector3d u = up(p);
    Eigen::Vector2d q = p;
    for (int iter = 0; iter < 32; ++iter) {
      std::optional<TinLocator::Hit> host;
      where_.visit(q, [&](const TinLocator::Hit& h) {
        if (!host) host = h;
      });
      if (!host) return std::nullopt;
      std::size_t face = host->triangle;
      if (flat(face)) {
        // No area on the surface (two corners on one of lat-long's pole rows, which is one
        // point): the ray meets a triangle round one of its corners, or leads towards one.
        std::optional<std::size_t> best;
        double bestInside = -INFINITY;
        for (const std::uint32_t c : t_.triangles[face])
          for (const std::uint32_t g : adj_.vertexFaces[c]) {
            const auto l = meeting(g, x, u);
            if (l && std::min({(*l)[0], (*l)[1], (*l)[2]}) > bestInside)
              bestInside = std::min({(*l)[0], (*l)[1], (*l)[2]}), best = g;
          }
        if (!best) return std::nullopt;
        face = *best;
      }
      const auto& tri = t_.triangles[face];
      // y, where the line meets the triangle's plane, by its barycentric coordinates.
      const std::optional<std::array<double, 3>> l = meeting(face, x, u);
      if (!l) return std::nullopt;
      double l0 = (*l)[0], l1 = (*l)[1], l2 = (*l)[2];
      const bool inside = std::min({l0, l1, l2}) >= -1e-12;
      if (!inside && iter < 31) {
        const Eigen::Vector2d next = l0 * t_.xy[tri[0]] + l1 * t_.xy[tri[1]] + l2 * t_.xy[tri[2]];
        if ((next - q).norm() > 1e-12) {
          q = next;
          continue;
        }
      }
      // Found, or circling between neighbours: the host triangle's nearest point.
      l0 = std::max(l0, 0.0), l1 = std::max(l1, 0.0), l2 = std::max(l2, 0.0);
      const double sum = l0 + l1 + l2;
      return onTriangle(tri, {l0 / sum, l1 / sum, l2 / sum});
    }
    return std::nullopt;
  }

  // Whether a terrain triangle has no area on the surface (its corners' points on one line: two
  // of them on one of lat-long's pole rows).
  bool flat(std::size_t face) const {
    const auto& tri = t_.triangles[face];
    const Eigen::Vector3d a = corner_[tri[1]] - corner_[tri[0]],
                          b = corner_[tri[2]] - corner_[tri[0]];
    return !(a.cross(b).norm() > 1e-12 * a.norm() * b.norm());
  }

  // The barycentric coordinates of the point where the line through x along u meets the plane
  // of terrain triangle `face` (nullopt for a flat one or one the line runs along).
  std::optional<std::array<double, 3>> meeting(std::size_t face, const Eigen::Vector3d& x,
                                               const Eigen::Vector3d& u) const {
    if (flat(face)) return std::nullopt;
    const auto& tri = t_.triangles[face];
    const Eigen::Vector3d &p0 = corner_[tri[0]], &p1 = corner_[tri[1]], &p2 = corner_[tri[2]];
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double across = n.dot(u);
    if (!(std::abs(across) > 1e-12 * n.norm())) return std::nullopt;
    const Eigen::Vector3d y = x + (n.dot(p0 - x) / across) * u;
    const double area2 = n.squaredNorm();
    const double l1 = n.dot((y - p0).cross(p2 - p0)) / area2;
    const double l2 = n.dot((p1 - p0).cross(y - p0)) / area2;
    return std::array<double, 3>{1.0 - l1 - l2, l1, l2};
  }

  // The point with barycentric coordinates l in terrain triangle tri, put exactly on an edge or
  // a corner when that close to one (so the triangulation sees it there, not a sliver beside it).
  OnMesh onTriangle(const std::array<std::uint32_t, 3>& tri, std::array<double, 3> l) const {
    constexpr double kOnSide = 1e-7;
    int small = 0, big = 0;
    for (int k = 0; k < 3; ++k) {
      if (l[std::size_t(k)] < kOnSide) ++small;
      if (l[std::size_t(k)] > l[std::size_t(big)]) big = k;
    }
    if (small >= 2) return {t_.xy[tri[std::size_t(big)]], corner_[tri[std::size_t(big)]]};
    if (small == 1) {
      const int zero = l[0] < kOnSide ? 0 : (l[1] < kOnSide ? 1 : 2);
      const std::uint32_t a = tri[std::size_t((zero + 1) % 3)],
                          b = tri[std::size_t((zero + 2) % 3)];
      const double s = l[std::size_t((zero + 2) % 3)] /
                       (l[std::size_t((zero + 1) % 3)] + l[std::size_t((zero + 2) % 3)]);
      return onEdge(a, b, s);
    }
    return {l[0] * t_.xy[tri[0]] + l[1] * t_.xy[tri[1]] + l[2] * t_.xy[tri[2]],
            l[0] * corner_[tri[0]] + l[1] * corner_[tri[1]] + l[2] * corner_[tri[2]]};
  }

  OnMesh onEdge(std::uint32_t a, std::uint32_t b, double s) const {
    s = std::round(s * kFraction) / kFraction;
    if (s <= 0) return {t_.xy[a], corner_[a]};
    if (s >= 1) return {t_.xy[b], corner_[b]};
    return {t_.xy[a] + s * (t_.xy[b] - t_.xy[a]), corner_[a] + s * (corner_[b] - corner_[a])};
  }

  // The mesh between a and b along the plane through both holding `normal`'s direction: the
  // points where it crosses terrain edges, in order; nullopt where the walk leaves the mesh.
  std::optional<std::vector<Eigen::Vector2d>> walk(const OnMesh& a, const OnMesh& b,
                                                   const Eigen::Vector3d& normal) const {
    const Eigen::Vector3d dir = b.at - a.at;
    const Eigen::Vector3d n = dir.cross(normal).normalized();
    if (!n.allFinite()) return std::nullopt;
    const double tiny = 1e-9 * dir.norm(), fEnd = dir.squaredNorm(), fTiny = 1e-9 * fEnd;
    const auto d = [&](std::uint32_t v) {
      const double s = n.dot(corner_[v] - a.at);
      return std::abs(s) <= tiny ? 0.0 : s;
    };
    const auto f = [&](const Eigen::Vector3d& x) { return dir.dot(x - a.at); };
    std::vector<std::uint32_t> endHosts;
    where_.visit(b.xy, [&](const TinLocator::Hit& h) { endHosts.push_back(h.triangle); });
    const auto isEnd = [&](std::int64_t face) {
      return std::find(endHosts.begin(), endHosts.end(), std::uint32_t(face)) != endHosts.end();
    };

    // A step's result: the point reached and what follows it (a triangle entered, or a vertex).
    struct Exit {
      OnMesh point;
      std::int64_t vertex = -1;      // reached a terrain vertex
      std::uint32_t e0 = 0, e1 = 0;  // else: crossed this terrain edge
      double f = -INFINITY;
    };
    // The forward exit from triangle `face` of a path standing at fNow.
    const auto exitOf = [&](std::size_t face, double fNow) {
      Exit best;
      const auto& tri = t_.triangles[face];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v0 = tri[std::size_t(k)], v1 = tri[std::size_t((k + 1) % 3)];
        const double d0 = d(v0), d1 = d(v1);
        Exit e;
        if (d0 == 0) {
          e.point = {t_.xy[v0], corner_[v0]}, e.vertex = v0;
        } else if ((d0 < 0) != (d1 < 0) && d1 != 0) {
          e.point = onEdge(v0, v1, d0 / (d0 - d1)), e.e0 = v0, e.e1 = v1;
          if (e.point.xy == t_.xy[v0]) e.vertex = v0;
          if (e.point.xy == t_.xy[v1]) e.vertex = v1;
        } else {
          continue;
        }
        e.f = f(e.point.at);
        if (e.f > fNow + fTiny && e.f > best.f) best = e;
      }
      return best;
    };

    std::vector<Eigen::Vector2d> points;
    std::vector<std::uint32_t> startHosts;
    where_.visit(a.xy, [&](const TinLocator::Hit& h) { startHosts.push_back(h.triangle); });
    for (const std::uint32_t s : startHosts)
      if (isEnd(s)) return points;  // a and b in one triangle: the straight edge is the drape
    Exit e;
    std::size_t face = 0;
    for (const std::uint32_t s : startHosts) {
      e = exitOf(s, f(a.at));
      face = s;
      if (e.f > -INFINITY) break;
    }
    if (!(e.f > -INFINITY)) return std::nullopt;
    for (int step = 0; step < kMaxSteps; ++step) {
      if (e.f >= fEnd - fTiny) return points;  // b lay in the triangle just crossed
      points.push_back(e.point.xy);
      if (e.vertex < 0) {
        const std::int64_t next = adj_.across(e.e0, e.e1, face);
        if (next < 0) return std::nullopt;
        if (isEnd(next)) return points;
        face = std::size_t(next);
        e = exitOf(face, e.f);
        if (!(e.f > -INFINITY)) return std::nullopt;
        continue;
      }
      // At a terrain vertex: on into the triangle around it that holds b, along a terrain edge
      // the plane holds, or across the far edge of the triangle the plane passes into.
      const std::uint32_t v = std::uint32_t(e.vertex);
      const double fv = e.f;
      Exit best;
      std::size_t bestFace = 0;
      for (const std::uint32_t g : adj_.vertexFaces[v]) {
        if (isEnd(g)) return points;
        const Exit x = exitOf(g, fv);
        if (x.f > best.f) best = x, bestFace = g;
      }
      if (!(best.f > -INFINITY)) return std::nullopt;
      e = best;
      face = bestFace;
    }
    return std::nullopt;
  }

 private:
  const SampleField& field_;
  const Tin& t_;
  const std::vector<Eigen::Vector3d>& corner_;
  const TinLocator& where_;
  Adjacency adj_;
};

bool onBorder(const Eigen::Vector2d& p, double xMax, double yMax) {
  return p.x() <= 0 || p.x() >= xMax || p.y() <= 0 || p.y() >= yMax;
}

bool alongBorder(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double xMax, double yMax) {
  return (a.x() <= 0 && b.x() <= 0) || (a.x() >= xMax && b.x() >= xMax) ||
         (a.y() <= 0 && b.y() <= 0) || (a.y() >= yMax && b.y() >= yMax);
}

}  // namespace

std::vector<Eigen::Vector2d> DrapedRoad::path(std::uint32_t a, std::uint32_t b) const {
  std::vector<Eigen::Vector2d> out{vertex[a]};
  const auto it = inner.find({std::min(a, b), std::max(a, b)});
  if (it != inner.end()) {
    if (a < b)
      out.insert(out.end(), it->second.begin(), it->second.end());
    else
      out.insert(out.end(), it->second.rbegin(), it->second.rend());
  }
  out.push_back(vertex[b]);
  return out;
}

bool drapeable(const SampleField& field, const Tin& terrain) {
  if (field.metric != ErrorMetric::kChart3d) return false;
  return std::all_of(terrain.xy.begin(), terrain.xy.end(), [](const Eigen::Vector2d& p) {
    return p.x() == std::floor(p.x()) && p.y() == std::floor(p.y()) && std::abs(p.x()) < 4e6 &&
           std::abs(p.y()) < 4e6;
  });
}

DrapedRoad drapeRoad(const SampleField& field, const Tin& terrain,
                     const std::vector<Eigen::Vector3d>& corner, const TinLocator& onTerrain,
                     const Road& road) {
  const double xMax = field.width - 1, yMax = field.height - 1;
  Draper draper(field, terrain, corner, onTerrain);
  DrapedRoad out;
  std::vector<OnMesh> at;
  for (const Eigen::Vector2d& p : road.xy) {
    const std::optional<OnMesh> blend = draper.blendAt(p);
    std::optional<OnMesh> moved;
    if (!onBorder(p, xMax, yMax)) moved = draper.normalOntoMesh(p);
    if (!blend) throw std::logic_error("drapeRoad: a road vertex lies outside the terrain mesh");
    if (moved) out.largestMoveM = std::max(out.largestMoveM, (moved->at - blend->at).norm());
    at.push_back(moved ? *moved : *blend);
    out.vertex.push_back(at.back().xy);
  }
  for (const auto& tri : road.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = std::min(tri[std::size_t(k)], tri[std::size_t((k + 1) % 3)]),
                          b = std::max(tri[std::size_t(k)], tri[std::size_t((k + 1) % 3)]);
      if (out.inner.count({a, b})) continue;
      auto& points = out.inner[{a, b}];
      if (alongBorder(road.xy[a], road.xy[b], xMax, yMax) || at[a].xy == at[b].xy) continue;
      const std::optional<std::vector<Eigen::Vector2d>> walked =
          draper.walk(at[a], at[b], draper.up(0.5 * (road.xy[a] + road.xy[b])));
      if (!walked) {
        ++out.straightEdges;
        continue;
      }
      for (const Eigen::Vector2d& p : *walked)
        if (p != at[a].xy && p != at[b].xy && (points.empty() || p != points.back()))
          points.push_back(p);
      if (!points.empty()) ++out.drapedEdges;
    }
  return out;
}

DrapedFootprint::DrapedFootprint(const DrapedRoad& drape,
                                 const std::vector<std::array<std::uint32_t, 3>>& tris,
                                 double width, double height)
    : bw_(std::max(1, int(std::ceil(width / bucket_)))),
      bh_(std::max(1, int(std::ceil(height / bucket_)))),
      buckets_(std::size_t(bw_) * std::size_t(bh_)) {
  const auto cell = [&](double x, int n) {
    return std::clamp(int(std::floor(x / bucket_)), 0, n - 1);
  };
  for (const auto& t : tris) {
    std::vector<Eigen::Vector2d> poly;
    for (int k = 0; k < 3; ++k) {
      const std::vector<Eigen::Vector2d> side =
          drape.path(t[std::size_t(k)], t[std::size_t((k + 1) % 3)]);
      poly.insert(poly.end(), side.begin(), side.end() - 1);
    }
    Eigen::Vector2d lo = poly[0], hi = poly[0];
    for (const auto& p : poly) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    for (int by = cell(lo.y(), bh_); by <= cell(hi.y(), bh_); ++by)
      for (int bx = cell(lo.x(), bw_); bx <= cell(hi.x(), bw_); ++bx)
        buckets_[std::size_t(by) * std::size_t(bw_) + std::size_t(bx)].push_back(
            std::uint32_t(polygon_.size()));
    polygon_.push_back(std::move(poly));
  }
}

bool DrapedFootprint::contains(const Eigen::Vector2d& p) const {
  const int bx = std::clamp(int(std::floor(p.x() / bucket_)), 0, bw_ - 1);
  const int by = std::clamp(int(std::floor(p.y() / bucket_)), 0, bh_ - 1);
  for (const std::uint32_t k : buckets_[std::size_t(by) * std::size_t(bw_) + std::size_t(bx)]) {
    const auto& poly = polygon_[k];
    bool inside = false;  // even-odd crossings of the ray towards +x
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      const Eigen::Vector2d &a = poly[i], &b = poly[j];
      if ((a.y() > p.y()) != (b.y() > p.y()) &&
          p.x() < a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
        inside = !inside;
    }
    if (inside) return true;
  }
  return false;
}

}  // namespace ps::tin
