// Issue 9's skips that need no OpenGL, each against doing the work: a tessellation handed back
// for an unchanged view and terrain is the mesh a fresh tessellation makes, and a tool that does
// not touch leaves the terrain alone (the replay skips the pipeline; a displacement sphere that
// does not reach the surface changes nothing when applied). The renderer's skips (culling,
// uploads, the overview's rate) are in test_render_ar_frame.cpp; erosion on active cells only is
// SandThermal/SandDiffusion.ActiveSetStepEqualsWholeGridStepBitForBit.
#include <gtest/gtest.h>

#include <cstring>

#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/displacement.hpp"
#include "short_scene.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"
#include "tracking/video.hpp"

using namespace ps;

namespace {

::testing::AssertionResult sameMesh(const terrain::Mesh& a, const terrain::Mesh& b) {
  if (a.eye != b.eye) return ::testing::AssertionFailure() << "eyes differ";
  if (a.gridIndex != b.gridIndex) return ::testing::AssertionFailure() << "vertices differ";
  if (a.indices != b.indices) return ::testing::AssertionFailure() << "triangles differ";
  if (a.positions.size() != b.positions.size() ||
      std::memcmp(a.positions.data(), b.positions.data(),
                  a.positions.size() * sizeof(Eigen::Vector3f)) != 0) {
    return ::testing::AssertionFailure() << "positions differ";
  }
  return ::testing::AssertionSuccess();
}

}  // namespace

TEST(Skips, AReusedTessellationIsTheMeshAFreshOneMakes) {
  auto planet = testkit::bumpyTerrain(8, 21, 8000.0);
  const double R = planet.chart().sphereRadius();
  const auto cam = terrain::Camera::lookAt({1.4 * R, 0.5 * R, 0.6 * R}, {0, 0, 0},
                                           Eigen::Vector3d::UnitZ(), 320, 240, 0.9);
  terrain::Tessellator kept;
  kept.tessellate(planet, cam, {});
  const auto generation = kept.mesh().generation;
  const terrain::Mesh& again = kept.tessellate(planet, cam, {});
  EXPECT_TRUE(kept.stats().reused);
  EXPECT_EQ(again.generation, generation);  // untouched: the renderer uploads nothing
  EXPECT_TRUE(sameMesh(again, terrain::Tessellator().tessellate(planet, cam, {})));

  // An edit under the same view is not skipped, and the new mesh is again a fresh one's.
  edit::EditPipeline pipe(planet);
  edit::BrushSettings s;
  s.radius = 0.2 * R;
  s.strength = 30000;
  pipe.apply(edit::GaussianBrush(s), {planet.chart().position(100, 128, 0.0), 0.0});
  const terrain::Mesh& edited = kept.tessellate(planet, cam, {});
  EXPECT_FALSE(kept.stats().reused);
  EXPECT_NE(edited.generation, generation);
  EXPECT_TRUE(sameMesh(edited, terrain::Tessellator().tessellate(planet, cam, {})));
  // Other settings under the same view and terrain are not skipped either.
  terrain::TessellationSettings finer;
  finer.distMaxPx = 1.0;
  kept.tessellate(planet, cam, finer);
  EXPECT_FALSE(kept.stats().reused);
  EXPECT_TRUE(sameMesh(kept.mesh(), terrain::Tessellator().tessellate(planet, cam, finer)));
}

TEST(Skips, AToolThatDoesNotTouchLeavesTheTerrainAlone) {
  // The replay (and the live app) run no edit work on frames where the tool does not touch.
  auto planet = testkit::bumpyTerrain(7, 4, 3000.0);
  auto options = testkit::shortSceneOptions();
  options.tool = replay::ReplayTool::kDisplace;
  options.settle = false;  // settling moves sand on its own; here only the tool's work counts
  tracking::FrameSource src(testkit::shortSceneVideo());
  replay::FrameStepper stepper(testkit::shortSceneCamera().forImageSize(src.size()), planet,
                               options);
  cv::Mat image;
  int touching = 0, notTouching = 0;
  while (src.read(image)) {
    const std::vector<float> before(planet.heights().begin(), planet.heights().end());
    const auto revision = planet.revision();
    const auto r = stepper.step(image, src.index(), src.index() / src.fps());
    if (r.touching) {
      ++touching;
      continue;
    }
    notTouching += r.scene.tipValid;
    EXPECT_EQ(planet.revision(), revision) << "frame " << src.index();
    EXPECT_TRUE(edittest::sameBits(before, planet.heights())) << "frame " << src.index();
  }
  EXPECT_GT(touching, 0);
  EXPECT_GT(notTouching, 0) << "the scene never shows the tool away from the surface";

  // Doing the work anyway: a displacement sphere held above the surface, applied, changes no
  // height and reports an empty dirty region (no bounds work).
  auto other = testkit::bumpyTerrain(7, 5, 3000.0);
  edit::EditPipeline pipe(other);
  sand::DisplacementSettings ds;
  ds.radius = 400e3;
  sand::DisplacementTool tool(other.chartPtr(), ds);
  const std::vector<float> before(other.heights().begin(), other.heights().end());
  for (const auto& c : {core::GridPoint{40, 64}, core::GridPoint{0, 1}, core::GridPoint{9, 127}}) {
    const Eigen::Vector3d up = other.chart().up(c.u, c.v);
    const double h = double(other.heights()[other.grid().index(c.u, c.v)]);
    // Centre 1.5 radii above the surface (relief 3 km, radius 400 km: never reaches it).
    pipe.apply(tool, {other.chart().position(c.u, c.v, h) + 1.5 * ds.radius * up, 0.0});
    EXPECT_TRUE(pipe.lastReport().dirty.empty()) << c.u << "," << c.v;
  }
  EXPECT_TRUE(edittest::sameBits(before, other.heights()));
}
