// The region TIN drawn in the view: the 4-8 mesh's triangles inside the region left out, the
// TIN's put in, the join closed by skirts. Measured geometrically: rays from a grazing camera
// through the pixels around the join, each tested against every triangle (brute force); a ray
// that meets the unspliced mesh and misses the spliced one would show the background.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include "edit/edit_pipeline.hpp"
#include "mesh_checks.hpp"
#include "sand/tin_sand_tool.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/terrain.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

// Whether the ray o + t d (t > 0) meets any triangle of the mesh.
bool hits(const terrain::Mesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    if (testkit::rayMeetsTriangle(mesh, t, o, d) < std::numeric_limits<double>::infinity())
      return true;
  }
  return false;
}

TEST(StrokeTinView, TheSplicedViewLeaksNoBackgroundThroughTheJoin) {
  const double R = 20e3;
  auto chart = sandtest::sphereChart(9, R);  // 513^2, 245 m cells
  terrain::Terrain t(chart, testkit::bumpyHeights(*chart, 3, 100.0));
  edit::EditPipeline pipe(t);
  sand::TinSandToolSettings s;
  s.radius = 1200.0;
  sand::TinSandTool tool(chart, s);
  const double lat = 15.0, lon = 40.0;
  pipe.beginStroke(tool, {edittest::latLon(lat, lon, R + 900.0, 1.0), 0.0});
  pipe.moveTo({edittest::latLon(lat, lon + 2.0, R + 900.0, 1.0), 0.0});
  pipe.endStroke();
  ASSERT_NE(tool.strokeTin(), nullptr);
  const terrain::MeshPatch patch = tool.strokeTin()->patch();

  std::size_t allLeaksNone = 0, allLeaksSkirts = 0;
  // Grazing cameras 9 km from the stroke's middle, from four sides, 1.5 km and 0.6 km above it.
  for (int view = 0; view < 8; ++view) {
    const Eigen::Vector3d target = edittest::latLon(lat, lon + 1.0, R, 1.0);
    const Eigen::Vector3d up = target.normalized();
    const Eigen::Vector3d east = Eigen::Vector3d::UnitZ().cross(up).normalized();
    const Eigen::Vector3d north = up.cross(east);
    const double az = M_PI / 2 * (view % 4) + 0.3;
    const Eigen::Vector3d away = std::cos(az) * east + std::sin(az) * north;
    const Eigen::Vector3d eye = target + 9000.0 * away + (view < 4 ? 1500.0 : 600.0) * up;
    const auto cam = terrain::Camera::lookAt(eye, target, up, 320, 240, 1.0);
    terrain::Tessellator tess;
    terrain::TessellationSettings ts;
    ts.distMaxPx = 2.0;
    ts.triangleBudget = 0;
    const terrain::Mesh& mesh = tess.tessellate(t, cam, ts);

    // Rays through the pixels around every region point near the TIN's border (where the join
    // is), 3 x 3 pixels each.
    const auto& region = *tool.strokeTin();
    const double cell = M_PI * R / chart->grid().m();
    std::vector<Eigen::Vector2d> pixels;
    for (const auto& q : region.points()) {
      if (region.sand().tin().depthInside(q.xy) > 3 * cell) continue;
      const Eigen::Vector3d c = cam.toCamera(chart->position(q.u, q.v, t.height(q.u, q.v)));
      if (c.z() <= 0) continue;
      const Eigen::Vector2d px = cam.project(c);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) pixels.push_back(px + Eigen::Vector2d(dx, dy));
    }
    ASSERT_GT(pixels.size(), 300u);
    const Eigen::Vector3d o = cam.eye - mesh.eye;
    const auto ray = [&](const Eigen::Vector2d& px) {
      const Eigen::Vector3d c((px.x() - cam.cx) / cam.fx, (px.y() - cam.cy) / cam.fy, 1.0);
      return Eigen::Vector3d(cam.rotation.transpose() * c);
    };
    std::size_t onPlanet = 0, leaksNone = 0, leaksSkirts = 0;
    terrain::Mesh none, skirts;
    const auto repNone =
        terrain::splicePatch(mesh, patch, *chart, terrain::PatchJoin::kNone, 0, none);
    const auto repSkirts =
        terrain::splicePatch(mesh, patch, *chart, terrain::PatchJoin::kSkirts, 20.0, skirts);
    ASSERT_GT(repNone.dropped, 100u) << "the view's triangles inside the region left out";
    ASSERT_GT(repSkirts.borderEdges, 20u);
    for (const Eigen::Vector2d& px : pixels) {
      const Eigen::Vector3d d = ray(px);
      if (!hits(mesh, o, d)) continue;
      ++onPlanet;
      leaksNone += !hits(none, o, d);
      leaksSkirts += !hits(skirts, o, d);
    }
    std::cout << "view " << view << ": " << mesh.triangleCount() << " view triangles, "
              << repNone.dropped << " left out, " << repNone.patchTriangles << " TIN triangles, "
              << repSkirts.borderEdges << " border edges; " << onPlanet
              << " rays on the planet at the join: " << leaksNone << " leak without skirts, "
              << leaksSkirts << " with 20 m skirts\n";
    EXPECT_GT(onPlanet, 200u);
    allLeaksNone += leaksNone;
    allLeaksSkirts += leaksSkirts;
  }
  std::cout << "all views: " << allLeaksNone << " leaks without skirts, " << allLeaksSkirts
            << " with\n";
  EXPECT_EQ(allLeaksSkirts, 0u);
  EXPECT_EQ(allLeaksNone, 0u) << "the overlap ring alone closes the join on these views";
}

}  // namespace
