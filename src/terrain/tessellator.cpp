#include "terrain/tessellator.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "terrain/diamond.hpp"

namespace ps::terrain {

namespace {

constexpr double kNear = 0.01;  // metres; balls reaching closer to the eye plane always split

constexpr std::uint8_t kAllPlanes = 0x1f;
constexpr std::uint8_t kHorizonClear = 0x20;

struct ViewGeometry {
  Eigen::Vector3d planes[5];  // camera-frame unit normals; plane 4 is the near plane (offset kNear)
  // f * kappa, where kappa bounds |X|/z over the image grown by distMax pixels: the screen
  // displacement of a 3D displacement d at X is at most f |X| / z^2 |d| <= f kappa |d| / z.
  double focalKappa;
  double focal;  // max(fx, fy)
  // Horizon (occluder: the sphere of radius R + min height, which is solid).
  bool horizonCull;
  Eigen::Vector3d towardCentre;  // unit, from eye
  double horizonPlaneDist;       // along towardCentre
  double sinCone, cosCone;       // of the occluder cone's half angle
};

ViewGeometry makeView(const Camera& c, double occluderRadius, double distMax) {
  ViewGeometry g;
  // Pixel extents [-1, W] x [-1, H]: a little beyond the image, so culling is conservative.
  g.planes[0] = Eigen::Vector3d(c.fx, 0, c.cx + 1).normalized();
  g.planes[1] = Eigen::Vector3d(-c.fx, 0, c.width - c.cx).normalized();
  g.planes[2] = Eigen::Vector3d(0, c.fy, c.cy + 1).normalized();
  g.planes[3] = Eigen::Vector3d(0, -c.fy, c.height - c.cy).normalized();
  g.planes[4] = Eigen::Vector3d(0, 0, 1);
  // A displacement whose projection reaches distMax pixels stays, up to that moment, within the
  // image grown by distMax (+1 for pixel edges); kappa is the largest |X|/z there.
  const double grow = distMax + 1;
  const double tx = std::max(std::abs(-grow - c.cx), std::abs(c.width + grow - c.cx)) / c.fx;
  const double ty = std::max(std::abs(-grow - c.cy), std::abs(c.height + grow - c.cy)) / c.fy;
  g.focal = std::max(c.fx, c.fy);
  g.focalKappa = g.focal * std::sqrt(1 + tx * tx + ty * ty);
  const double d = c.eye.norm();
  g.horizonCull = occluderRadius > 0 && d > occluderRadius * (1 + 1e-9);
  if (g.horizonCull) {
    g.towardCentre = -c.eye / d;
    g.horizonPlaneDist = (d * d - occluderRadius * occluderRadius) / d;
    g.sinCone = occluderRadius / d;
    g.cosCone = std::sqrt(std::max(0.0, 1 - g.sinCone * g.sinCone));
  }
  return g;
}

// True when every point of the ball (w = centre - eye, radius r) is hidden behind the occluder:
// it lies beyond the horizon plane and inside the cone of rays that hit the sphere. Inside the
// cone means the ball's centre is at least r from the cone's surface: with `along` the centre's
// distance along the axis and `across` its distance from it, along sin(alpha) - across
// cos(alpha) >= r (the angle form theta + beta <= alpha, with one root and no division).
inline bool behindHorizon(const ViewGeometry& g, const Eigen::Vector3d& w, double along, double r) {
  if (along - r < g.horizonPlaneDist) return false;
  const double across = std::sqrt(std::max(0.0, w.squaredNorm() - along * along));
  return along * g.sinCone - across * g.cosCone >= r;
}

// What the split test decides for a triangle seen wholly in view. Culling, for the few
// triangles at the view's edges, comes after and can only turn kSplitLeafChildren into kSplit.
enum SplitDecision : std::uint8_t {
  kNoSplit = 0,
  kSplit = 1,
  kSplitLeafChildren = 2,  // splits, and its children's errors cannot split them: emit them
};

struct SplitTest {
  double forward[3];  // the camera's viewing direction, planet frame
  double focalKappa, focal, distMax;
  bool childrenKnown;  // childError holds the children's largest error code
};

// The split test of a whole level (one triangle per split vertex) at once: a loop over arrays
// that the compiler vectorises, where one triangle at a time spent most of its instructions
// moving scalars in and out of vector registers. x, y, z hold the split vertices' positions and
// leave relative to the eye. Every clone performs the same IEEE operations in the same order
// (no fused multiply-adds: -ffp-contract=off), so the decisions, and the mesh, do not depend on
// the machine. Returns how many triangles split.
__attribute__((target_clones("avx512f", "avx2", "default"))) std::size_t decideSplits(
    const SplitTest& t, const Eigen::Vector3d& eye, std::size_t count, double* __restrict x,
    double* __restrict y, double* __restrict z, const std::uint16_t* __restrict errorCode,
    const std::uint16_t* __restrict radiusCode, const std::uint16_t* __restrict childCode,
    std::uint8_t* __restrict decision) {
  const double f0 = t.forward[0], f1 = t.forward[1], f2 = t.forward[2];
  const double ex = eye.x(), ey = eye.y(), ez = eye.z();
  const double fk = t.focalKappa, fo = t.focal, dm = t.distMax;
  const int childrenKnown = t.childrenKnown ? 1 : 0;
  std::size_t splitting = 0;
  // Integer logic instead of && and ?: keeps the loop free of branches, which it must be to
  // vectorise.
  for (std::size_t i = 0; i < count; ++i) {
    const double wx = x[i] - ex, wy = y[i] - ey, wz = z[i] - ez;
    x[i] = wx, y[i] = wy, z[i] = wz;
    const double eps = BoundCode::decode(errorCode[i]);
    const double r = double(BoundCode::decode(radiusCode[i])) + eps;
    const double zc = (f0 * wx + f1 * wy) + f2 * wz;
    const double zr = zc - r;
    const double reach = std::sqrt((wx * wx + wy * wy) + wz * wz) + r;  // >= |X| on the ball
    const double limit = dm * zr, limit2 = limit * zr;
    // Whether an error e on this ball can reach distMax on screen: two valid bounds, the smaller
    // decides (both are nested, so their minimum is too); see the class comment.
    const int errorSplits = int(fk * eps > limit) & int(fo * eps * reach > limit2);
    // A ball wholly behind the near plane shows nothing (culling drops it too): its error
    // cannot reach the screen, so it never needs to split. One reaching closer to the eye
    // plane than kNear always splits.
    const int splits = int(eps > 0) & int(zc + r >= kNear) & (int(zr <= kNear) | errorSplits);
    // The children's split vertices carry at most childError, and their balls lie inside this
    // one (nesting, with the radius margin that keeps the tests monotone in floating point), so
    // the same test with childError bounds theirs.
    const double child = BoundCode::decode(childCode[i]);
    const int childSplits = int(fk * child > limit) & int(fo * child * reach > limit2);
    const int leafChildren = childrenKnown & int(zr > kNear) & (childSplits ^ 1);
    decision[i] = std::uint8_t(splits * (1 + leafChildren));
    splitting += std::size_t(splits);
  }
  return splitting;
}

// A triangle at the view's edges: its ball (w = centre - eye, radius r) culled by a frustum plane
// or the horizon, or the planes it lies wholly inside learned into `inside` (its children
// inherit them).
enum class EdgeTest { kKept, kCulledFrustum, kCulledHorizon };
inline EdgeTest testAtViewEdges(const ViewGeometry& view, const Eigen::Matrix3d& R,
                                const Eigen::Vector3d& w, double r, std::uint8_t& inside) {
  const Eigen::Vector3d cam = R * w;
  for (int p = 0; p < 5; ++p) {
    if (inside & (1u << p)) continue;
    const double d = view.planes[p].dot(cam) - (p == 4 ? kNear : 0.0);
    if (d < -r) return EdgeTest::kCulledFrustum;
    if (d >= r) inside |= std::uint8_t(1u << p);
  }
  if (!(inside & kHorizonClear)) {
    const double along = view.horizonCull ? w.dot(view.towardCentre) : 0.0;
    if (!view.horizonCull || along + r < view.horizonPlaneDist) {
      inside |= kHorizonClear;  // wholly in front of the horizon plane: children too
    } else if (behindHorizon(view, w, along, r)) {
      return EdgeTest::kCulledHorizon;
    }
  }
  return EdgeTest::kKept;
}

}  // namespace

void Tessellator::SplitVertices::growTo(std::size_t n) {
  if (u.size() >= n) return;
  for (auto* a : {&u, &v}) a->resize(n);
  height.resize(n);
  for (auto* a : {&error, &radius, &childError}) a->resize(n);
  for (auto* a : {&x, &y, &z}) a->resize(n);
  decision.resize(n);
}

// Grid coordinates fit 16 bits (Tessellator::Corner) and grid indices 32 (the vertex hash).
static_assert(core::GridSize::kMaxLevel <= 15);

std::uint32_t Tessellator::addVertex(std::uint64_t gridIndex,
                                     const Eigen::Vector3d& relativeToEye) {
  const auto index = std::uint32_t(mesh_.gridIndex.size());
  mesh_.gridIndex.push_back(gridIndex);
  mesh_.positions.push_back(relativeToEye.cast<float>());
  return index;
}

void Tessellator::startLevelHash(std::size_t nodes) {
  std::size_t slots = 1024;
  while (slots <= nodes) slots *= 2;  // an empty slot always remains: probing ends
  if (hash_.size() < slots) hash_.resize(slots);
  hashMask_ = slots - 1;
  std::fill_n(hash_.begin(), slots, HashSlot{kEmpty, 0});
}

std::uint32_t Tessellator::vertexFor(std::uint64_t gridIndex,
                                     const Eigen::Vector3d& relativeToEye) {
  const auto key = std::uint32_t(gridIndex);
  std::size_t slot = hashSlot(key);
  while (hash_[slot].key != key && hash_[slot].key != kEmpty) slot = (slot + 1) & hashMask_;
  if (hash_[slot].key == key) return hash_[slot].value;
  const std::uint32_t index = addVertex(gridIndex, relativeToEye);
  hash_[slot] = {key, index};
  return index;
}

bool Tessellator::loadSplitVertices(const Terrain& terrain, int depth) {
  const std::vector<Node>& level = levelNodes_;
  const std::size_t count = level.size();
  split_.growTo(count);
  std::int32_t* su = split_.u.data();
  std::int32_t* sv = split_.v.data();
  float* height = split_.height.data();
  std::uint16_t* errorCode = split_.error.data();
  std::uint16_t* radiusCode = split_.radius.data();
  std::uint16_t* childCode = split_.childError.data();
  const core::GridSize g = terrain.grid();
  const int halfSize = g.m() >> (depth / 2 + 1);
  // Lattice entries know their children's largest error; the full arrays do not.
  const bool childrenKnown = halfSize >= (1 << ErrorBounds::kLatticeShift);
  if (childrenKnown) {
    const ErrorBounds::LatticeLevel lattice =
        terrain.bounds().latticeLevel(halfSize, depth % 2 == 0);
    for (std::size_t i = 0; i < count; ++i) {
      const Node& n = level[i];
      const int cu = (n.b0.u + n.b1.u) / 2, cv = (n.b0.v + n.b1.v) / 2;
      const LatticeEntry& e = lattice.at(cu, cv);
      su[i] = cu, sv[i] = cv;
      height[i] = e.height;
      errorCode[i] = e.codes.error, radiusCode[i] = e.codes.radius;
      childCode[i] = e.childError;
    }
  } else {
    const float* h = terrain.heights().data();
    const BoundCodes* codes = terrain.bounds().codes().data();
    for (std::size_t i = 0; i < count; ++i) {
      const Node& n = level[i];
      const int uu = n.b0.u + n.b1.u, vv = n.b0.v + n.b1.v;
      const bool onGrid = ((uu | vv) & 1) == 0;  // the hypotenuse has a midpoint on the grid
      const std::size_t ci = onGrid ? g.index(uu / 2, vv / 2) : 0;
      su[i] = uu / 2, sv[i] = vv / 2;
      height[i] = h[ci];
      // Off the grid, a zero error: the triangle cannot split.
      errorCode[i] = onGrid ? codes[ci].error : 0;
      radiusCode[i] = codes[ci].radius;
      childCode[i] = 0;
    }
  }
  return childrenKnown;
}

template <class ChartT>
bool Tessellator::pass(const ChartT& chart, const Terrain& terrain, const Camera& camera,
                       double distMax, bool cull, std::size_t abortAbove) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const float* h = terrain.heights().data();
  // The occluder is the ball under the lowest height of a sphere about the origin; a chart
  // that is no such sphere (sphereRadius() 0: flat, torus, cylinder) has none, whatever its
  // heights.
  const double occluder =
      chart.sphereRadius() > 0 ? chart.sphereRadius() + terrain.minHeight() : 0.0;
  const ViewGeometry view = makeView(camera, occluder, distMax);
  const Eigen::Matrix3d& R = camera.rotation;
  const Eigen::Vector3d forward = R.row(2).transpose();
  const Eigen::Vector3d eye = camera.eye;

  mesh_.clear();
  mesh_.eye = eye;
  mesh_.generation = nextMeshGeneration();
  stats_.visited = stats_.culledFrustum = stats_.culledHorizon = stats_.leafPairsUnvisited = 0;

  auto corner = [&](GridPoint p) {
    const std::size_t k = g.index(p.u, p.v);
    return addVertex(k, chart.position(p.u, p.v, double(h[k])) - eye);
  };
  const std::uint32_t c00 = corner({0, 0}), cmm = corner({m, m}), c0m = corner({0, m}),
                      cm0 = corner({m, 0});

  // Breadth first, one level of the bintree at a time: every split vertex of a level is known
  // before any is tested, so their heights and bounds are loaded in one tight loop whose loads
  // overlap, instead of one at a time as a depth-first walk reaches them (each a likely cache
  // miss on an 8193^2 planet). The split decisions depend on the vertex alone, so the mesh
  // holds the same triangles whatever the order.
  std::vector<Node>& level = levelNodes_;
  std::vector<Node>& next = nextNodes_;
  level.clear();
  const std::uint8_t startInside = cull ? 0 : std::uint8_t(kAllPlanes | kHorizonClear);
  // Two root triangles over the main diagonal, CCW in (u, v) = CCW seen from outside.
  const auto mm = std::uint16_t(m);
  level.push_back({{0, mm}, {0, 0}, {mm, mm}, c0m, c00, cmm, startInside});
  level.push_back({{mm, 0}, {mm, mm}, {0, 0}, cm0, cmm, c00, startInside});

  // Level 2k of the bintree splits at the centres of half-size m / 2^(k+1), level 2k + 1 at the
  // edges of that half-size.
  for (int depth = 0; !level.empty(); ++depth) {
    const std::size_t count = level.size();
    const bool childrenKnown = loadSplitVertices(terrain, depth);
    const std::int32_t* su = split_.u.data();
    const std::int32_t* sv = split_.v.data();
    const std::uint16_t* errorCode = split_.error.data();
    const std::uint16_t* radiusCode = split_.radius.data();
    double* x = split_.x.data();
    double* y = split_.y.data();
    double* z = split_.z.data();
    chart.scatteredPositions(su, sv, split_.height.data(), count, {x, y, z});
    const SplitTest test{{forward.x(), forward.y(), forward.z()},
                         view.focalKappa,
                         view.focal,
                         distMax,
                         childrenKnown};
    std::uint8_t* decision = split_.decision.data();
    const std::size_t splitting = decideSplits(test, eye, count, x, y, z, errorCode, radiusCode,
                                               split_.childError.data(), decision);

    next.clear();
    startLevelHash(splitting);
    stats_.visited += count;
    for (std::size_t i = 0; i < count; ++i) {
      const Node& n = level[i];
      std::uint8_t split = decision[i];
      std::uint8_t inside = n.inside;
      const bool onGrid = (((n.b0.u + n.b1.u) | (n.b0.v + n.b1.v)) & 1) == 0;
      if (inside != (kAllPlanes | kHorizonClear) && onGrid) {
        const double r =
            double(BoundCode::decode(radiusCode[i])) + double(BoundCode::decode(errorCode[i]));
        const EdgeTest edge =
            testAtViewEdges(view, R, Eigen::Vector3d(x[i], y[i], z[i]), r, inside);
        if (edge != EdgeTest::kKept) {
          ++(edge == EdgeTest::kCulledFrustum ? stats_.culledFrustum : stats_.culledHorizon);
          continue;
        }
        // Children emitted without a visit skip their own culling: only where none is left.
        if (split == kSplitLeafChildren && inside != (kAllPlanes | kHorizonClear)) split = kSplit;
      }
      if (split == kNoSplit) {
        mesh_.indices.push_back(n.ia);
        mesh_.indices.push_back(n.ib0);
        mesh_.indices.push_back(n.ib1);
        continue;
      }
      const std::uint32_t ic = vertexFor(g.index(su[i], sv[i]), Eigen::Vector3d(x[i], y[i], z[i]));
      if (split == kSplitLeafChildren) {
        // Both children are leaves (55 % of the leaves of the budget-bound orbit view).
        mesh_.indices.insert(mesh_.indices.end(), {ic, n.ia, n.ib0, ic, n.ib1, n.ia});
        ++stats_.leafPairsUnvisited;
        continue;
      }
      const Corner split16{std::uint16_t(su[i]), std::uint16_t(sv[i])};
      next.push_back({split16, n.a, n.b0, ic, n.ia, n.ib0, inside});
      next.push_back({split16, n.b1, n.a, ic, n.ib1, n.ia, inside});
    }
    // A pending triangle that is not culled ends as one triangle or more, and culling takes few
    // of a level's (those at the frustum's and the horizon's edges): half the pending count
    // towards the limit. Stopping early only costs a retry at a coarser threshold, never a
    // wrong mesh.
    if (abortAbove && mesh_.triangleCount() + next.size() / 2 > abortAbove) return false;
    std::swap(level, next);
  }
  return true;
}

const Mesh& Tessellator::tessellate(const Terrain& terrain, const Camera& camera,
                                    const TessellationSettings& settings) {
  camera.validate();
  if (!terrain.bounds().hasRadii()) {
    // Without radii every triangle would project as a point: a silently wrong mesh.
    throw std::logic_error(
        "tessellate: the terrain's bounds were built without radii "
        "(BoundsContent::kErrorsOnly, for exports)");
  }
  if (!std::isfinite(settings.distMaxPx) || settings.distMaxPx <= 0) {
    throw core::InputError("dist_max " + std::to_string(settings.distMaxPx) +
                           " px must be positive and finite");
  }
  if (cacheValid_ && cachedRevision_ == terrain.revision() && cachedCamera_ == camera &&
      cachedSettings_ == settings) {
    stats_.reused = true;
    return mesh_;
  }
  cacheValid_ = false;
  stats_.reused = false;
  double distMax = settings.distMaxPx;
  const std::size_t budget = settings.triangleBudget;
  // Successive views are close, so when the budget bound last time with these settings, start
  // from the threshold it settled on. A start that leaves the mesh well under the budget (the
  // view got simpler) falls back to the requested threshold, so the view is never left much
  // coarser than the budget requires.
  constexpr double kCoherentFill = 0.8;
  stats_.coherentStart = budget && budgetStart_ > distMax && cachedSettings_ == settings;
  if (stats_.coherentStart) distMax = budgetStart_;
  // When the budget binds, the whole view coarsens: raise the threshold (triangle counts
  // scale roughly with 1/distMax) and tessellate again.
  constexpr int kMaxPasses = 16;
  stats_.passes = 0;
  for (;;) {
    ++stats_.passes;
    const std::size_t abortAbove = budget ? 4 * budget : 0;
    bool complete;
    if (auto* ll = dynamic_cast<const core::LatLongChart*>(&terrain.chart())) {
      complete = pass(*ll, terrain, camera, distMax, settings.cull, abortAbove);
    } else {
      complete = pass(terrain.chart(), terrain, camera, distMax, settings.cull, abortAbove);
    }
    const std::size_t tris = mesh_.triangleCount();
    if (complete && stats_.passes == 1 && stats_.coherentStart &&
        double(tris) < kCoherentFill * double(budget)) {
      distMax = settings.distMaxPx;  // the view got simpler: search from the request again
      continue;
    }
    if (budget == 0 || (complete && tris <= budget) || stats_.passes >= kMaxPasses) break;
    distMax *= complete ? std::max(1.02, 1.03 * double(tris) / double(budget)) : 4.0;
  }
  budgetStart_ = distMax > settings.distMaxPx ? distMax : 0.0;
  stats_.effectiveDistMaxPx = distMax;
  stats_.triangles = mesh_.triangleCount();
  stats_.vertices = mesh_.gridIndex.size();
  cacheValid_ = true;
  cachedRevision_ = terrain.revision();
  cachedCamera_ = camera;
  cachedSettings_ = settings;
  return mesh_;
}

}  // namespace ps::terrain
