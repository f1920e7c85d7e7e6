#include "terrain/tessellator.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "terrain/diamond.hpp"

namespace ps::terrain {

namespace {

constexpr double kNear = 0.01;  // metres; balls reaching closer to the eye plane always split

struct Node {
  GridPoint a, b0, b1;
  std::uint8_t inside;  // bit i: ball known to lie inside frustum plane i; bit 5: in front of the
                        // horizon plane
};

constexpr std::uint8_t kAllPlanes = 0x1f;
constexpr std::uint8_t kHorizonClear = 0x20;

struct ViewGeometry {
  Eigen::Vector3d planes[5];  // camera-frame unit normals; plane 4 is the near plane (offset kNear)
  double focal;
  // Horizon (occluder: the sphere of radius R + min height, which is solid).
  bool horizonCull;
  Eigen::Vector3d towardCentre;  // unit, from eye
  double horizonPlaneDist;       // along towardCentre
  double sinCone;                // sin of the occluder cone's half angle
  double cosCone;
};

ViewGeometry makeView(const Camera& c, double occluderRadius) {
  ViewGeometry g;
  // Pixel extents [-1, W] x [-1, H]: a little beyond the image, so culling is conservative.
  g.planes[0] = Eigen::Vector3d(c.fx, 0, c.cx + 1).normalized();
  g.planes[1] = Eigen::Vector3d(-c.fx, 0, c.width - c.cx).normalized();
  g.planes[2] = Eigen::Vector3d(0, c.fy, c.cy + 1).normalized();
  g.planes[3] = Eigen::Vector3d(0, -c.fy, c.height - c.cy).normalized();
  g.planes[4] = Eigen::Vector3d(0, 0, 1);
  g.focal = std::max(c.fx, c.fy);
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
// it lies beyond the horizon plane and inside the cone of rays that hit the sphere.
bool behindHorizon(const ViewGeometry& g, const Eigen::Vector3d& w, double r) {
  const double along = w.dot(g.towardCentre);
  if (along - r < g.horizonPlaneDist) return false;
  const double dist = w.norm();
  if (dist <= r) return false;
  // theta + beta <= alpha, with cos(theta) = along/dist, sin(beta) = r/dist, sin(alpha) = sinCone.
  const double cosT = along / dist, sinT = std::sqrt(std::max(0.0, 1 - cosT * cosT));
  const double sinB = r / dist, cosB = std::sqrt(std::max(0.0, 1 - sinB * sinB));
  // cos(theta + beta) >= cos(alpha)
  return cosT * cosB - sinT * sinB >= g.cosCone;
}

}  // namespace

template <class ChartT>
bool Tessellator::pass(const ChartT& chart, const Terrain& terrain, const Camera& camera,
                       double distMax, bool cull, std::size_t abortAbove) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  const float* h = terrain.heights().data();
  const BoundCodes* codes = terrain.bounds().codes().data();
  const ViewGeometry view = makeView(camera, chart.radius() + terrain.minHeight());
  const Eigen::Matrix3d& R = camera.rotation;
  const Eigen::Vector3d eye = camera.eye;

  triangleCorners_.clear();
  stats_.visited = stats_.culledFrustum = stats_.culledHorizon = 0;

  std::vector<Node> stack;
  stack.reserve(256);
  const std::uint8_t startInside = cull ? 0 : std::uint8_t(kAllPlanes | kHorizonClear);
  // Two root triangles over the main diagonal, CCW in (u, v) = CCW seen from outside.
  stack.push_back({{0, m}, {0, 0}, {m, m}, startInside});
  stack.push_back({{m, 0}, {m, m}, {0, 0}, startInside});

  while (!stack.empty()) {
    const Node n = stack.back();
    stack.pop_back();
    ++stats_.visited;
    const int su = n.b0.u + n.b1.u, sv = n.b0.v + n.b1.v;
    bool split = false;
    std::uint8_t inside = n.inside;
    if (((su | sv) & 1) == 0) {  // the hypotenuse has a midpoint on the grid
      const GridPoint c{su / 2, sv / 2};
      const std::size_t ci = g.index(c.u, c.v);
      const BoundCodes bc = codes[ci];
      const double eps = BoundCode::decode(bc.error);
      const double r = double(BoundCode::decode(bc.radius)) + eps;
      const Eigen::Vector3d w = chart.position(c.u, c.v, double(h[ci])) - eye;
      const Eigen::Vector3d cam = R * w;
      if (inside != (kAllPlanes | kHorizonClear)) {
        bool outside = false;
        for (int i = 0; i < 5 && !outside; ++i) {
          if (inside & (1u << i)) continue;
          const double d = view.planes[i].dot(cam) - (i == 4 ? kNear : 0.0);
          if (d < -r)
            outside = true;
          else if (d >= r)
            inside |= std::uint8_t(1u << i);
        }
        if (outside) {
          ++stats_.culledFrustum;
          continue;
        }
        if (!(inside & kHorizonClear)) {
          if (!view.horizonCull) {
            inside |= kHorizonClear;
          } else if (w.dot(view.towardCentre) + r < view.horizonPlaneDist) {
            inside |= kHorizonClear;  // wholly in front of the horizon plane: children too
          } else if (behindHorizon(view, w, r)) {
            ++stats_.culledHorizon;
            continue;
          }
        }
      }
      if (eps > 0) {
        const double zr = cam.z() - r;
        if (zr <= kNear) {
          split = true;
        } else {
          split = view.focal * eps * (w.norm() + r) > distMax * zr * zr;
        }
      }
      if (split) {
        stack.push_back({c, n.b1, n.a, inside});
        stack.push_back({c, n.a, n.b0, inside});
        continue;
      }
    }
    triangleCorners_.push_back(g.index(n.a.u, n.a.v));
    triangleCorners_.push_back(g.index(n.b0.u, n.b0.v));
    triangleCorners_.push_back(g.index(n.b1.u, n.b1.v));
    if (abortAbove && triangleCorners_.size() > 3 * abortAbove) return false;
  }
  return true;
}

void Tessellator::buildVertices(const Terrain& terrain, const Camera& camera) {
  mesh_.clear();
  mesh_.eye = camera.eye;
  const std::size_t tris = triangleCorners_.size() / 3;
  std::size_t cap = std::bit_ceil(std::max<std::size_t>(64, 2 * tris + 8));
  hashKeys_.assign(cap, ~std::uint64_t(0));
  hashValues_.resize(cap);
  mesh_.indices.resize(triangleCorners_.size());
  const core::GridSize g = terrain.grid();
  const auto side = std::uint64_t(g.side());
  const core::Chart& chart = terrain.chart();
  for (std::size_t i = 0; i < triangleCorners_.size(); ++i) {
    const std::uint64_t key = triangleCorners_[i];
    std::size_t slot = std::size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & (cap - 1);
    while (hashKeys_[slot] != key && hashKeys_[slot] != ~std::uint64_t(0))
      slot = (slot + 1) & (cap - 1);
    if (hashKeys_[slot] != key) {
      hashKeys_[slot] = key;
      hashValues_[slot] = std::uint32_t(mesh_.gridIndex.size());
      mesh_.gridIndex.push_back(key);
      const int u = int(key % side), v = int(key / side);
      const Eigen::Vector3d p = chart.position(u, v, double(terrain.heights()[key])) - camera.eye;
      mesh_.positions.push_back(p.cast<float>());
    }
    mesh_.indices[i] = hashValues_[slot];
  }
  stats_.triangles = tris;
  stats_.vertices = mesh_.gridIndex.size();
}

const Mesh& Tessellator::tessellate(const Terrain& terrain, const Camera& camera,
                                    const TessellationSettings& settings) {
  camera.validate();
  if (!std::isfinite(settings.distMaxPx) || settings.distMaxPx <= 0) {
    throw core::InputError("dist_max " + std::to_string(settings.distMaxPx) +
                           " px must be positive and finite");
  }
  if (cacheValid_ && cachedRevision_ == terrain.revision() && cachedCamera_ == camera &&
      cachedSettings_ == settings) {
    stats_.reused = true;
    return mesh_;
  }
  stats_.reused = false;
  double distMax = settings.distMaxPx;
  const std::size_t budget = settings.triangleBudget;
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
    const std::size_t tris = triangleCorners_.size() / 3;
    if (budget == 0 || (complete && tris <= budget)) break;
    if (stats_.passes >= kMaxPasses) {
      // Keep the first `budget` triangles' worth of coarsening honest: report the overrun.
      break;
    }
    distMax *= complete ? std::max(1.02, 1.03 * double(tris) / double(budget)) : 4.0;
  }
  stats_.effectiveDistMaxPx = distMax;
  buildVertices(terrain, camera);
  cacheValid_ = true;
  cachedRevision_ = terrain.revision();
  cachedCamera_ = camera;
  cachedSettings_ = settings;
  return mesh_;
}

}  // namespace ps::terrain
