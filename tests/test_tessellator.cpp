#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/input_error.hpp"
#include "mesh_checks.hpp"
#include "terrain/screen_error.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"

using namespace ps;
using terrain::Camera;
using terrain::TessellationSettings;
using terrain::Tessellator;

namespace {

// A random camera: some from orbit, some skimming the surface, some looking at a pole or
// along the seam.
Camera randomCameraAnyAltitude(std::mt19937& rng, double R, int width = 640, int height = 480) {
  std::uniform_real_distribution<double> uni(-1, 1), unit(0, 1);
  Eigen::Vector3d dir(uni(rng), uni(rng), uni(rng));
  const int kind = int(rng() % 4);
  if (kind == 1) dir = Eigen::Vector3d(0.01 * uni(rng), 0.01 * uni(rng), 1);  // over the north pole
  if (kind == 2) dir = Eigen::Vector3d(-1, 0.01 * uni(rng), 0.3 * uni(rng));  // over the seam
  dir.normalize();
  const double altitude = R * std::pow(10.0, -4 + 4.5 * unit(rng));  // 0.0001 R .. 3 R
  const Eigen::Vector3d eye = dir * (R + 9000 + altitude);
  Eigen::Vector3d target =
      (unit(rng) < 0.5)
          ? Eigen::Vector3d::Zero()
          : Eigen::Vector3d(dir * R + R * 0.3 * Eigen::Vector3d(uni(rng), uni(rng), uni(rng)));
  if ((target - eye).norm() < 1) target = Eigen::Vector3d::Zero();
  return Camera::lookAt(eye, target, Eigen::Vector3d(0.3, 0.1, 1), width, height,
                        0.5 + 1.2 * unit(rng));
}

}  // namespace

TEST(Tessellator, WholePlanetMeshIsCrackFreeForManyViews) {
  for (int n : {5, 7}) {
    const auto t = testkit::bumpyTerrain(n, 3, 60000.0);
    std::mt19937 rng(100 + n);
    Tessellator tess;
    for (int i = 0; i < 25; ++i) {
      const Camera cam = randomCameraAnyAltitude(rng, testkit::kEarthRadius);
      TessellationSettings s;
      s.cull = false;
      s.triangleBudget = 0;
      s.distMaxPx = 0.5 + 8 * (i % 4);
      const auto& mesh = tess.tessellate(t, cam, s);
      ASSERT_GT(mesh.triangleCount(), 0u);
      ASSERT_EQ(testkit::conformityDefect(t, mesh), "") << "n=" << n << " view " << i;
    }
  }
}

TEST(Tessellator, FullResolutionMeshIsCrackFreeAndComplete) {
  const auto t = testkit::bumpyTerrain(5, 4, 20000.0);
  Camera cam =
      Camera::lookAt({0, 0, 3 * testkit::kEarthRadius}, {0, 0, 0}, {1, 0, 0}, 640, 480, 1.0);
  TessellationSettings s;
  s.cull = false;
  s.triangleBudget = 0;
  s.distMaxPx = 1e-9;  // every vertex with a non-zero error splits
  Tessellator tess;
  const auto& mesh = tess.tessellate(t, cam, s);
  // Only triangles whose vertices all sit on one pole may stay unsplit: the mesh is the surface.
  EXPECT_LT(terrain::measureTrueError(t, mesh), 1e-6);
  EXPECT_GE(mesh.triangleCount(), 2u * 32 * 32 - 2 * 32);
  EXPECT_EQ(testkit::conformityDefect(t, mesh), "");
}

TEST(Tessellator, MeasuredScreenErrorNeverExceedsDistMax) {
  const auto t = testkit::bumpyTerrain(7, 9, 40000.0);
  std::mt19937 rng(77);
  Tessellator tess;
  int meaningful = 0;
  for (int i = 0; i < 40; ++i) {
    const Camera cam = randomCameraAnyAltitude(rng, testkit::kEarthRadius);
    TessellationSettings s;
    s.triangleBudget = 0;
    s.distMaxPx = std::pow(2.0, -1 + int(rng() % 6));  // 0.5 .. 16 px
    const auto& mesh = tess.tessellate(t, cam, s);
    const auto rep = terrain::measureScreenError(t, cam, mesh);
    ASSERT_LE(rep.maxPx, s.distMaxPx) << "view " << i << " triangles " << mesh.triangleCount();
    if (rep.verticesChecked > 100 && rep.maxPx > 0.2 * s.distMaxPx) ++meaningful;
  }
  EXPECT_GE(meaningful, 5) << "too few views where the bound was actually approached";
}

namespace {

// The split rule of tessellator.hpp, depth first, one triangle at a time, without culling: the
// set of triangles (grid indices, rotated to start at the smallest) the tessellator must emit.
std::vector<std::array<std::uint64_t, 3>> referenceMesh(const terrain::Terrain& t,
                                                        const Camera& cam, double distMax) {
  constexpr double kNear = 0.01;
  const double grow = distMax + 1;
  const double tx =
      std::max(std::abs(-grow - cam.cx), std::abs(cam.width + grow - cam.cx)) / cam.fx;
  const double ty =
      std::max(std::abs(-grow - cam.cy), std::abs(cam.height + grow - cam.cy)) / cam.fy;
  const double focal = std::max(cam.fx, cam.fy);
  const double focalKappa = focal * std::sqrt(1 + tx * tx + ty * ty);
  const Eigen::Vector3d forward = cam.rotation.row(2).transpose();
  const auto g = t.grid();
  std::vector<std::array<std::uint64_t, 3>> out;
  auto emit = [&](core::GridPoint a, core::GridPoint b0, core::GridPoint b1) {
    std::array<std::uint64_t, 3> tri{g.index(a.u, a.v), g.index(b0.u, b0.v), g.index(b1.u, b1.v)};
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  };
  auto splits = [&](core::GridPoint c) {
    const std::size_t i = g.index(c.u, c.v);
    const double eps = t.bounds().error(i);
    const double r = double(t.bounds().radius(i)) + eps;
    const Eigen::Vector3d w = t.chart().position(c.u, c.v, double(t.heights()[i])) - cam.eye;
    const double zc = forward.dot(w);
    if (!(eps > 0 && zc + r >= kNear)) return false;
    const double zr = zc - r;
    return zr <= kNear ||
           (focalKappa * eps > distMax * zr && focal * eps * (w.norm() + r) > distMax * zr * zr);
  };
  auto visit = [&](auto&& self, core::GridPoint a, core::GridPoint b0, core::GridPoint b1) -> void {
    const int su = b0.u + b1.u, sv = b0.v + b1.v;
    if (((su | sv) & 1) == 0 && splits({su / 2, sv / 2})) {
      const core::GridPoint c{su / 2, sv / 2};
      self(self, c, a, b0);
      self(self, c, b1, a);
      return;
    }
    emit(a, b0, b1);
  };
  const int m = g.m();
  visit(visit, {0, m}, {0, 0}, {m, m});
  visit(visit, {m, 0}, {m, m}, {0, 0});
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::array<std::uint64_t, 3>> sortedTriangles(const terrain::Mesh& mesh) {
  std::vector<std::array<std::uint64_t, 3>> out;
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    std::array<std::uint64_t, 3> tri{mesh.gridIndex[mesh.indices[3 * k]],
                                     mesh.gridIndex[mesh.indices[3 * k + 1]],
                                     mesh.gridIndex[mesh.indices[3 * k + 2]]};
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

// The breadth-first tessellator, with its shortcuts (children proven leaves from their parent's
// ball are emitted without a visit), emits exactly the triangles the split rule gives when it is
// applied to every triangle, depth first.
TEST(Tessellator, EmitsExactlyTheSplitRulesTriangles) {
  const auto t = testkit::bumpyTerrain(9, 5, 30000.0);
  std::mt19937 rng(9);
  Tessellator tess;
  std::size_t unvisited = 0;
  for (int i = 0; i < 12; ++i) {
    const Camera cam = randomCameraAnyAltitude(rng, testkit::kEarthRadius);
    TessellationSettings s;
    s.cull = false;
    s.triangleBudget = 0;
    s.distMaxPx = std::pow(2.0, -1 + int(rng() % 5));  // 0.5 .. 8 px
    const auto& mesh = tess.tessellate(t, cam, s);
    ASSERT_EQ(sortedTriangles(mesh), referenceMesh(t, cam, s.distMaxPx))
        << "view " << i << ", " << mesh.triangleCount() << " triangles";
    unvisited += tess.stats().leafPairsUnvisited;
  }
  EXPECT_GT(unvisited, 1000u) << "the shortcut must have been taken";
}

TEST(Tessellator, BudgetCoarsensTheWholeViewAndStaysBounded) {
  const auto t = testkit::bumpyTerrain(10, 2, 30000.0);
  const Camera cam = Camera::lookAt({0, -2.0 * testkit::kEarthRadius, 0.2 * testkit::kEarthRadius},
                                    {0, 0, 0}, {0, 0, 1}, 1280, 720, 1.0);
  Tessellator tess;
  TessellationSettings s;
  s.distMaxPx = 0.5;
  s.triangleBudget = 0;
  const std::size_t unlimited = tess.tessellate(t, cam, s).triangleCount();
  ASSERT_GT(unlimited, 5000u);
  s.triangleBudget = unlimited / 4;
  const auto& mesh = tess.tessellate(t, cam, s);
  EXPECT_LE(mesh.triangleCount(), s.triangleBudget);
  EXPECT_GT(mesh.triangleCount(), s.triangleBudget / 3) << "budget used, not wasted";
  EXPECT_GT(tess.stats().effectiveDistMaxPx, s.distMaxPx);
  const auto rep = terrain::measureScreenError(t, cam, mesh);
  EXPECT_LE(rep.maxPx, tess.stats().effectiveDistMaxPx)
      << "coarsened evenly: one raised threshold holds everywhere";
}

// Frame coherence: a budget that bound on the last call starts the next one at the threshold it
// settled on (one pass for the same view), and a view that no longer needs the raise gets the
// requested threshold back, exactly as a fresh tessellator would mesh it.
TEST(Tessellator, BoundBudgetStartsTheNextCallWhereItSettled) {
  const auto t = testkit::bumpyTerrain(10, 2, 30000.0);
  const Camera near = Camera::lookAt({0, -2.0 * testkit::kEarthRadius, 0.2 * testkit::kEarthRadius},
                                     {0, 0, 0}, {0, 0, 1}, 1280, 720, 1.0);
  TessellationSettings s;
  s.distMaxPx = 0.5;
  s.triangleBudget = 0;
  const std::size_t unlimited = Tessellator().tessellate(t, near, s).triangleCount();
  s.triangleBudget = unlimited / 4;

  Tessellator tess;
  const std::vector<std::uint32_t> first = tess.tessellate(t, near, s).indices;
  const double settled = tess.stats().effectiveDistMaxPx;
  ASSERT_GE(tess.stats().passes, 2) << "the budget must bind for this test";
  EXPECT_FALSE(tess.stats().coherentStart);

  tess.invalidate();
  EXPECT_EQ(tess.tessellate(t, near, s).indices, first);
  EXPECT_TRUE(tess.stats().coherentStart);
  EXPECT_EQ(tess.stats().passes, 1);
  EXPECT_EQ(tess.stats().effectiveDistMaxPx, settled);

  // From far away the request fits the budget: the raised start is dropped.
  const Camera far =
      Camera::lookAt({0, -80.0 * testkit::kEarthRadius, 0}, {0, 0, 0}, {0, 0, 1}, 1280, 720, 1.0);
  const auto& mesh = tess.tessellate(t, far, s);
  EXPECT_TRUE(tess.stats().coherentStart);
  EXPECT_EQ(tess.stats().effectiveDistMaxPx, s.distMaxPx);
  EXPECT_EQ(mesh.indices, Tessellator().tessellate(t, far, s).indices);
  // And the next call starts from the request again.
  tess.invalidate();
  tess.tessellate(t, far, s);
  EXPECT_FALSE(tess.stats().coherentStart);
  EXPECT_EQ(tess.stats().passes, 1);
}

TEST(Tessellator, CullingSkipsWorkAndUnchangedViewsAreReused) {
  const auto t = testkit::bumpyTerrain(8, 2, 8000.0);
  const Camera cam = Camera::lookAt({0, 0, testkit::kEarthRadius + 500000},
                                    {0, testkit::kEarthRadius, 0}, {0, 0, 1}, 1280, 720, 1.0);
  Tessellator culled, unculled;
  TessellationSettings s;
  s.triangleBudget = 0;
  const auto& a = culled.tessellate(t, cam, s);
  EXPECT_GT(culled.stats().culledFrustum + culled.stats().culledHorizon, 0u);
  s.cull = false;
  const auto& b = unculled.tessellate(t, cam, s);
  EXPECT_LT(a.triangleCount(), b.triangleCount() / 2);
  s.cull = true;
  const auto* before = a.indices.data();
  const auto& again = culled.tessellate(t, cam, s);
  EXPECT_TRUE(culled.stats().reused);
  EXPECT_EQ(again.indices.data(), before);
  Camera moved = cam;
  moved.eye.x() += 1.0;
  culled.tessellate(t, moved, s);
  EXPECT_FALSE(culled.stats().reused);
}

TEST(Tessellator, PositionsAreEyeRelativeAndPreciseNearTheCamera) {
  const auto t = testkit::bumpyTerrain(9, 6, 8000.0);
  // 1 m above the surface vertex at the equator.
  const int m = t.grid().m();
  const Eigen::Vector3d ground = t.chart().position(m / 2, m / 2, t.height(m / 2, m / 2));
  const Eigen::Vector3d eye = ground * (1 + 1.0 / ground.norm());
  const Camera cam =
      Camera::lookAt(eye, ground + Eigen::Vector3d(0, 50, 0), {0, 0, 1}, 640, 480, 1.2);
  Tessellator tess;
  const auto& mesh = tess.tessellate(t, cam, {});
  bool sawGround = false;
  for (std::size_t i = 0; i < mesh.gridIndex.size(); ++i) {
    const auto gi = mesh.gridIndex[i];
    const int u = int(gi % t.grid().side()), v = int(gi / t.grid().side());
    const Eigen::Vector3d truth = t.chart().position(u, v, t.height(u, v)) - eye;
    // Float keeps relative precision: error well below a millimetre at a metre.
    ASSERT_LE((mesh.positions[i].cast<double>() - truth).norm(), 1e-6 * truth.norm() + 1e-9);
    if (u == m / 2 && v == m / 2) sawGround = true;
  }
  EXPECT_TRUE(sawGround);
}

TEST(Tessellator, RejectsDegenerateCamerasAndSettings) {
  const auto t = testkit::bumpyTerrain(5);
  Tessellator tess;
  Camera c = Camera::lookAt({0, 0, 2e7}, {0, 0, 0}, {1, 0, 0}, 640, 480, 1.0);
  Camera bad = c;
  bad.fx = 0;
  EXPECT_THROW(tess.tessellate(t, bad, {}), core::InputError);
  bad = c;
  bad.width = 0;
  EXPECT_THROW(tess.tessellate(t, bad, {}), core::InputError);
  bad = c;
  bad.eye.x() = NAN;
  EXPECT_THROW(tess.tessellate(t, bad, {}), core::InputError);
  bad = c;
  bad.rotation(0, 0) = 2;
  EXPECT_THROW(tess.tessellate(t, bad, {}), core::InputError);
  TessellationSettings s;
  s.distMaxPx = 0;
  EXPECT_THROW(tess.tessellate(t, c, s), core::InputError);
  s.distMaxPx = NAN;
  EXPECT_THROW(tess.tessellate(t, c, s), core::InputError);
}
