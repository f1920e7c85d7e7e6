#include "sand/tin_sand.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "core/input_error.hpp"
#include "tin/triangle_error.hpp"

namespace ps::sand {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool segmentsCross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

// Whether p lies inside the closed polygon (crossing number).
bool insidePolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Eigen::Vector2d &a = poly[i], &b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      inside = !inside;
  }
  return inside;
}

double polygonDistance(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  double best = INFINITY;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    best = std::min(best, tin::pointSegmentDistance(p, poly[j], poly[i]));
  return best;
}

// The rampart's profile (paper 004's): 1 at the outer contour, 0 at the rampart's edge.
double rampartProfile(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return 1.0 - 3.0 * t * t + 2.0 * t * t * t;
}

}  // namespace

TinStampTool TinStampTool::disc(double radius, int segments) {
  TinStampTool t;
  for (int k = 0; k < segments; ++k) {
    const double a = 2.0 * std::numbers::pi * k / segments;
    t.outline.emplace_back(radius * std::cos(a), radius * std::sin(a));
  }
  t.rim = 0.05 * radius;
  t.rampartWidth = radius;
  return t;
}

void TinStampTool::validate() const {
  const std::size_t n = outline.size();
  if (n < 3)
    throw core::InputError("stamp tool: its outline has " + std::to_string(n) +
                           " points; it needs at least 3");
  for (std::size_t i = 0; i < n; ++i) {
    if (!outline[i].allFinite())
      throw core::InputError("stamp tool: outline point " + std::to_string(i) + " is not finite");
    if (outline[i].norm() == 0)
      throw core::InputError("stamp tool: outline point " + std::to_string(i) +
                             " is the tool's centre");
    if (outline[i] == outline[(i + 1) % n])
      throw core::InputError("stamp tool: outline points " + std::to_string(i) + " and " +
                             std::to_string((i + 1) % n) + " are the same point (degenerate)");
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;
      if (segmentsCross(outline[i], outline[(i + 1) % n], outline[j], outline[(j + 1) % n]))
        throw core::InputError("stamp tool: the outline intersects itself (edges " +
                               std::to_string(i) + " and " + std::to_string(j) + " cross)");
    }
  for (std::size_t i = 0; i < n; ++i)
    if (!(cross(outline[i], outline[(i + 1) % n]) > 0))
      throw core::InputError("stamp tool: edge " + std::to_string(i) +
                             " does not turn counter-clockwise about the centre (the outline "
                             "must be counter-clockwise and seen whole from its centre)");
  if (!(std::isfinite(rim) && rim > 0))
    throw core::InputError("stamp tool: rim " + core::exactNumber(rim) + " m must be positive");
  if (!(std::isfinite(rampartWidth) && rampartWidth > 0))
    throw core::InputError("stamp tool: rampart width " + core::exactNumber(rampartWidth) +
                           " m must be positive");
}

double TinStampTool::outerRadius() const {
  double r = 0;
  for (const Eigen::Vector2d& q : outline) r = std::max(r, q.norm() + rim);
  return r;
}

void TinSandSettings::validate() const {
  material.validate();
  if (!(std::isfinite(flatDeg) && flatDeg > 0 && flatDeg <= 10))
    throw core::InputError("flat angle " + core::exactNumber(flatDeg) +
                           " degrees is outside (0, 10]");
  if (idleSteps < 1 || idleSteps > 100)
    throw core::InputError("idle steps " + std::to_string(idleSteps) + " is outside 1 .. 100");
}

TinSand::TinSand(tin::DynamicTin tin, TinSandSettings settings)
    : tin_(std::move(tin)), settings_(std::move(settings)) {
  settings_.validate();
  tanTalus_ = settings_.material.tanTalus();
  tanFlat_ = std::tan(settings_.flatDeg * std::numbers::pi / 180.0);
}

void TinSand::activate(Vertex v, bool changed) {
  if (v >= inLe_.size()) {
    inLe_.resize(std::size_t(v) + 1, 0);
    idle_.resize(std::size_t(v) + 1, 0);
  }
  idle_[v] = 0;
  if (!inLe_[v]) inLe_[v] = 1, le_.push_back(v);
  if (changed) markFlatCandidate(v);
}

void TinSand::markFlatCandidate(Vertex v) {
  if (v >= inLr_.size()) inLr_.resize(std::size_t(v) + 1, 0);
  if (!inLr_[v]) inLr_[v] = 1, lr_.push_back(v);
}

// One stamp's contours: the tool's polygons at the stamp and the TIN's vertices along them.
struct TinSand::StampContours {
  std::vector<Eigen::Vector2d> inner, outer;  // the tool's outline and its rim's outer edge
  std::vector<Vertex> innerIds, outerIds;     // the polygons' corners in the TIN
  std::vector<Vertex> innerPath, outerPath;   // vertices where they cross older contours
  // Older constrained edges freed near the stamp (3D end points).
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> freed;
  double snap = 0;  // a contour point this close to a vertex takes that vertex

  bool onInner(Vertex v) const { return has(innerIds, v) || has(innerPath, v); }
  bool onContour(Vertex v) const { return onInner(v) || has(outerIds, v) || has(outerPath, v); }

 private:
  static bool has(const std::vector<Vertex>& ids, Vertex v) {
    return std::find(ids.begin(), ids.end(), v) != ids.end();
  }
};

TinStampStats TinSand::stamp(const Eigen::Vector2d& centre, double bottom,
                             const TinStampTool& tool) {
  const auto t0 = Clock::now();
  tool.validate();
  if (!centre.allFinite() || !std::isfinite(bottom))
    throw core::InputError("stamp: its centre or bottom height is not finite");
  const double reach = tool.reach();
  if (tin_.depthInside(centre) < reach)
    throw core::InputError("stamp: the tool reaches " + core::exactNumber(reach) +
                           " m from its centre, beyond the TIN's region there");
  TinStampStats stats;
  const double before = tin_.volume();
  ++generation_;
  const StampContours contours = placeContours(centre, bottom, tool, stats);

  tin_.verticesWithin(centre, tool.outerRadius(), scratch_);
  const std::vector<Vertex> inside = pressInside(contours, scratch_, bottom, stats);
  removeFlatInside(contours, inside, bottom, stats);
  removeWallVertices(contours, scratch_, centre, tool, stats);

  const double displaced = before - tin_.volume();
  stats.displacedVolume = displaced;
  if (tool.pushAside) pushAside(contours, centre, tool, displaced);
  timing_.stampMs += msSince(t0);
  return stats;
}

// Outer contour first: it follows the terrain. Then the inner one, pressed. Then, when the tool
// pushes aside, rings halfway across the rampart and at its edge, so that the material pushed
// aside lands in the rampart's profile however coarse the TIN is there (and not beyond its edge).
TinSand::StampContours TinSand::placeContours(const Eigen::Vector2d& centre, double bottom,
                                              const TinStampTool& tool, TinStampStats& stats) {
  StampContours c;
  const std::size_t n = tool.outline.size();
  c.inner.resize(n), c.outer.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d& q = tool.outline[k];
    c.inner[k] = centre + q;
    c.outer[k] = centre + q * (1.0 + tool.rim / q.norm());
  }
  // Contour points may snap to vertices up to `snap` outside the outer contour: free what
  // their edges could cross too.
  c.snap = 0.25 * tool.rim;
  stats.freedConstraints =
      tin_.freeConstraintsNear(centre, tool.outerRadius() + 2 * c.snap, &c.freed);

  const std::size_t countBefore = tin_.vertexCount();
  c.outerIds.resize(n), c.innerIds.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    c.outerIds[k] = placeContourPoint(c.outer[k], INFINITY, c.snap);
  for (std::size_t k = 0; k < n; ++k)
    constrainAcrossFreed(c.outerIds[k], c.outerIds[(k + 1) % n], INFINITY, c, c.outerPath);
  for (std::size_t k = 0; k < n; ++k) c.innerIds[k] = placeContourPoint(c.inner[k], bottom, c.snap);
  for (std::size_t k = 0; k < n; ++k)
    constrainAcrossFreed(c.innerIds[k], c.innerIds[(k + 1) % n], bottom, c, c.innerPath);
  for (const double across : {0.5, 1.0})
    for (std::size_t k = 0; k < n && tool.pushAside; ++k) {
      const Eigen::Vector2d& q = tool.outline[k];
      placeContourPoint(centre + q * (1.0 + (tool.rim + across * tool.rampartWidth) / q.norm()),
                        INFINITY, c.snap);
    }
  stats.inserted = tin_.vertexCount() - countBefore;
  return c;
}

// A contour point next to a vertex already there (an earlier stamp's) takes that vertex instead
// of making a sliver beside it; its height is capped at `cap`.
TinSand::Vertex TinSand::placeContourPoint(const Eigen::Vector2d& p, double cap, double snap) {
  const Vertex near = tin_.vertexNear(p, snap);
  if (near == tin::DynamicTin::kNoVertex) return tin_.insert(p, std::min(tin_.heightAt(p), cap));
  tin_.setHeight(near, std::min(tin_.height(near), cap));
  return near;
}

// Where a contour edge crosses an older contour's (freed) edge, a vertex at the older edge's
// height there (capped): the crease where the two imprints meet stays in the TIN (the freed
// edge's line is the surface before this stamp along it), and the wall is not cut across.
void TinSand::constrainAcrossFreed(Vertex from, Vertex to, double cap, const StampContours& c,
                                   std::vector<Vertex>& path) {
  const Eigen::Vector2d p = tin_.position(from), q = tin_.position(to);
  const double length = (q - p).norm();
  std::vector<std::pair<double, Eigen::Vector3d>> crossings;
  for (const auto& [a3, b3] : c.freed) {
    const Eigen::Vector2d a = a3.head<2>(), b = b3.head<2>();
    if (!segmentsCross(p, q, a, b)) continue;
    const double den = cross(q - p, b - a);
    const double s = cross(a - p, b - a) / den, u = cross(a - p, q - p) / den;
    if (s * length < c.snap || (1 - s) * length < c.snap) continue;
    crossings.emplace_back(s, Eigen::Vector3d(p.x() + s * (q - p).x(), p.y() + s * (q - p).y(),
                                              (1 - u) * a3.z() + u * b3.z()));
  }
  std::sort(crossings.begin(), crossings.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  Vertex at = from;
  double last = 0;
  for (const auto& [s, x] : crossings) {
    if ((s - last) * length < c.snap) continue;
    const Eigen::Vector2d xy = x.head<2>();
    Vertex v = tin_.vertexNear(xy, c.snap);
    if (v == tin::DynamicTin::kNoVertex)
      v = tin_.insert(xy, std::min(x.z(), cap));
    else
      tin_.setHeight(v, std::min(tin_.height(v), cap));
    if (v == at || v == to) continue;
    tin_.constrain(at, v, generation_);
    path.push_back(v);
    at = v, last = s;
  }
  if (at != to) tin_.constrain(at, to, generation_);
}

// Presses everything inside the inner contour down to the bottom; wakes it and the contours.
std::vector<TinSand::Vertex> TinSand::pressInside(const StampContours& c,
                                                  const std::vector<Vertex>& nearby, double bottom,
                                                  TinStampStats& stats) {
  std::vector<Vertex> inside;
  for (const Vertex v : nearby) {
    if (!insidePolygon(c.inner, tin_.position(v))) continue;
    inside.push_back(v);
    if (tin_.height(v) > bottom) tin_.setHeight(v, bottom), ++stats.pressed;
  }
  for (const Vertex v : inside) activate(v);
  for (const Vertex v : c.outerIds) activate(v);
  for (const Vertex v : c.outerPath) activate(v);
  for (const Vertex v : c.innerPath) activate(v);
  return inside;
}

// Inner vertices on the bottom with no deeper neighbour carry nothing the contour does not.
void TinSand::removeFlatInside(const StampContours& c, const std::vector<Vertex>& inside,
                               double bottom, TinStampStats& stats) {
  for (const Vertex v : inside) {
    if (c.onContour(v)) continue;
    if (tin_.height(v) != bottom) continue;
    tin_.neighbours(v, neighbours_);
    // A vertex on a constrained edge (where this stamp's contour crossed one) stays: it carries
    // the contour.
    if (std::any_of(neighbours_.begin(), neighbours_.end(), [&](Vertex u) {
          return tin_.height(u) < bottom || tin_.generation(v, u) != tin::DynamicTin::kNoVertex;
        }))
      continue;
    if (tin_.remove(v)) ++stats.removedInside;
  }
}

// Older vertices between the contours (on the tool's wall) standing on or above the wall, the
// line across the rim from the inner contour to the outer one along their ray, carry nothing
// the contours do not: removed, the wall is the contours' own triangles. Those under it (an
// older, deeper imprint) stay. The volume this changes is in the stamp's own account.
void TinSand::removeWallVertices(const StampContours& c, const std::vector<Vertex>& nearby,
                                 const Eigen::Vector2d& centre, const TinStampTool& tool,
                                 TinStampStats& stats) {
  const std::size_t n = tool.outline.size();
  // Where v's ray d crosses the contour edge a-b (at lambda * d), and the height there.
  const auto crossing = [&](const Eigen::Vector2d& d, Vertex a, Vertex b, double& lambda,
                            double& h) {
    const Eigen::Vector2d pa = tin_.position(a) - centre, pb = tin_.position(b) - centre;
    const double den = cross(d, pb - pa);
    if (den == 0) return false;
    lambda = cross(pa, pb - pa) / den;
    const double u = std::clamp((lambda * d - pa).dot(pb - pa) / (pb - pa).squaredNorm(), 0.0, 1.0);
    h = (1 - u) * tin_.height(a) + u * tin_.height(b);
    return true;
  };
  for (const Vertex v : nearby) {
    if (!tin_.alive(v) || tin_.onHull(v) || c.onContour(v)) continue;
    const Eigen::Vector2d d = tin_.position(v) - centre;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t l = (k + 1) % n;
      if (cross(tool.outline[k], d) < 0 || cross(d, tool.outline[l]) <= 0) continue;
      double lIn = 0, hIn = 0, lOut = 0, hOut = 0;
      if (!crossing(d, c.innerIds[k], c.innerIds[l], lIn, hIn) ||
          !crossing(d, c.outerIds[k], c.outerIds[l], lOut, hOut) || !(lIn < 1 && 1 < lOut))
        break;
      const double t = (1 - lIn) / (lOut - lIn);
      if (t > 0.02 && t < 0.98 && tin_.height(v) >= hIn + t * (hOut - hIn) &&
          tin_.remove(v, nullptr, false))
        ++stats.removedWall;
      break;
    }
  }
}

// What the stamp changed goes onto the rampart, weighted by its profile.
void TinSand::pushAside(const StampContours& c, const Eigen::Vector2d& centre,
                        const TinStampTool& tool, double displaced) {
  tin_.verticesWithin(centre, tool.reach(), scratch_);
  std::vector<std::pair<Vertex, double>> rampart;
  double weighted = 0;
  for (const Vertex v : scratch_) {
    const Eigen::Vector2d p = tin_.position(v);
    // The inner contour's vertices lie on the polygon, where the inside test may go either way.
    if (insidePolygon(c.inner, p) || tin_.onHull(v) || c.onInner(v)) continue;
    const double t =
        insidePolygon(c.outer, p) ? 0.0 : polygonDistance(c.outer, p) / tool.rampartWidth;
    const double profile = rampartProfile(t);
    if (profile <= 0) continue;
    rampart.emplace_back(v, profile);
    weighted += profile * tin_.weight(v);
  }
  if (weighted > 0 && displaced != 0) {
    const double scale = displaced / weighted;
    for (const auto& [v, profile] : rampart) {
      tin_.setHeight(v, tin_.height(v) + scale * profile);
      activate(v);
    }
  }
}

std::size_t TinSand::erode() {
  const auto t0 = Clock::now();
  const double cohesion = settings_.material.cohesion;
  const double rate = settings_.material.erosionRate;
  const double restTolerance = settings_.material.talusTolerance * tanTalus_;
  std::size_t givers = 0;
  const std::vector<Vertex> round = le_;
  struct Share {
    Vertex v;
    double weight, amount, gap;
  };
  std::vector<Share> shares;
  for (const Vertex k : round) {
    if (!tin_.alive(k) || !inLe_[k]) continue;
    const double hk = tin_.height(k);
    const Eigen::Vector2d pk = tin_.position(k);
    tin_.neighbourhood(k, ring_);
    shares.clear();
    double excessSum = 0;
    for (const tin::DynamicTin::Neighbour& j : ring_) {
      const double d = (j.p - pk).norm();
      const double gap = hk - j.h;
      const double excess = gap - (tanTalus_ * d + cohesion);
      if (excess > restTolerance * d) {
        shares.push_back({j.v, weight(j.v), excess, gap});
        excessSum += excess;
      }
    }
    if (shares.empty()) {
      if (++idle_[k] >= settings_.idleSteps) inLe_[k] = 0;
      continue;
    }
    ++givers;
    idle_[k] = 0;
    // Each lower neighbour j would level its edge to the talus line alone with the volume
    // e_j / (1/w_k + 1/w_j); the giver moves c times its share of that (by excess) to each.
    const double wk = weight(k);
    double total = 0;
    for (Share& s : shares) {
      s.amount = rate * (s.amount / excessSum) * s.amount / (1.0 / wk + 1.0 / s.weight);
      total += s.amount;
    }
    // The giver stays at least as high as every receiver (no new extremum).
    double lambda = 1.0;
    for (const Share& s : shares)
      lambda = std::min(lambda, s.gap / (total / wk + s.amount / s.weight));
    if (!(lambda > 0)) continue;
    double given = 0;
    for (const Share& s : shares) {
      const double m = lambda * s.amount;
      tin_.setHeight(s.v, tin_.height(s.v) + m / s.weight);
      given += m;
      markFlatCandidate(s.v);
    }
    tin_.setHeight(k, hk - given / wk);
    markFlatCandidate(k);
    // The receivers rose and k sank: a higher neighbour may now be steeper than the talus. Lr
    // takes only the vertices whose height changed (the paper's step 2d); the others are woken.
    for (const tin::DynamicTin::Neighbour& j : ring_) activate(j.v, false);
  }
  // Vertices that went idle leave the list.
  le_.erase(
      std::remove_if(le_.begin(), le_.end(), [&](Vertex v) { return !tin_.alive(v) || !inLe_[v]; }),
      le_.end());
  timing_.erodeMs += msSince(t0);
  return givers;
}

double TinSand::weight(Vertex v) {
  if (v >= weight_.size())
    weight_.resize(std::size_t(v) + 1), weightEpoch_.resize(weight_.size(), 0);
  const std::uint64_t stamp = tin_.topologyEpoch() + 1;
  if (weightEpoch_[v] != stamp) weight_[v] = tin_.weight(v), weightEpoch_[v] = stamp;
  return weight_[v];
}

bool TinSand::isFlat(Vertex v) {
  const double h = tin_.height(v);
  const Eigen::Vector2d p = tin_.position(v);
  tin_.neighbourhood(v, ring_);
  for (const tin::DynamicTin::Neighbour& u : ring_)
    if (std::abs(u.h - h) > tanFlat_ * (u.p - p).norm()) return false;
  return true;
}

std::size_t TinSand::removeRedundant() {
  auto t0 = Clock::now();
  std::vector<Vertex> flat;
  for (const Vertex v : lr_) {
    inLr_[v] = 0;
    if (tin_.alive(v) && !tin_.onHull(v) && isFlat(v)) flat.push_back(v);
  }
  lr_.clear();
  timing_.detectMs += msSince(t0);
  if (!settings_.removeRedundant) return 0;
  t0 = Clock::now();
  std::size_t removed = 0;
  for (const Vertex v : flat) {
    // An earlier removal may have changed v's neighbours: test again.
    if (!tin_.alive(v) || !isFlat(v)) continue;
    tin_.neighbours(v, scratch_);
    if (!tin_.remove(v)) continue;
    if (v < inLe_.size()) inLe_[v] = 0;
    ++removed;
    for (const Vertex u : scratch_) activate(u);  // raised a little to keep the volume
  }
  le_.erase(
      std::remove_if(le_.begin(), le_.end(), [&](Vertex u) { return !tin_.alive(u) || !inLe_[u]; }),
      le_.end());
  timing_.removeMs += msSince(t0);
  return removed;
}

}  // namespace ps::sand
