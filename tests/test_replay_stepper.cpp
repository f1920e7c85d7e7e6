// replay::FrameStepper (the per-frame pipeline shared by runReplay and the live app): the same
// log lines and heights as runReplay, tool and brush changes between frames, and the planet
// turned by hand (live app) moving the AR pose and the tip together.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/input_error.hpp"
#include "replay/replay.hpp"
#include "sand/sand_grid.hpp"
#include "short_scene.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"
#include "tracking/synth.hpp"
#include "tracking/video.hpp"

using namespace ps;

using testkit::shortSceneCamera;
using testkit::shortSceneOptions;
using testkit::shortSceneVideo;

TEST(ReplayStepper, StepsWriteTheReplaysLogAndHeights) {
  auto a = testkit::bumpyTerrain(7, 4, 3000.0);
  tracking::FrameSource src(shortSceneVideo());
  std::ostringstream log;
  const auto summary = replay::runReplay(src, shortSceneCamera(), a, shortSceneOptions(), log);

  auto b = testkit::bumpyTerrain(7, 4, 3000.0);
  tracking::FrameSource src2(shortSceneVideo());
  replay::FrameStepper stepper(shortSceneCamera().forImageSize(src2.size()), b,
                               shortSceneOptions());
  std::string lines;
  cv::Mat image;
  int withPose = 0;
  while (src2.read(image)) {
    const auto r = stepper.step(image, src2.index(), src2.index() / src2.fps());
    lines += r.logLine + "\n";
    withPose += r.planetInCamera.has_value();
    if (r.touching) {
      ASSERT_TRUE(r.control.has_value());
    }
  }
  stepper.endStroke();
  EXPECT_EQ(lines, log.str());
  EXPECT_EQ(std::memcmp(a.heights().data(), b.heights().data(), a.heights().size() * sizeof(float)),
            0);
  EXPECT_EQ(stepper.summary().frames, summary.frames);
  EXPECT_EQ(stepper.summary().strokes, summary.strokes);
  EXPECT_GE(summary.strokes, 1);
  EXPECT_EQ(withPose, summary.framesWithPlanet);
}

TEST(ReplayStepper, TurnedPlanetMovesPoseAndTipTogether) {
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()) *
                                Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ()))
                                   .toRotationMatrix();
  auto a = testkit::bumpyTerrain(7, 4, 3000.0), b = testkit::bumpyTerrain(7, 4, 3000.0);
  tracking::FrameSource srcA(shortSceneVideo()), srcB(shortSceneVideo());
  replay::FrameStepper plain(shortSceneCamera().forImageSize(srcA.size()), a, shortSceneOptions());
  replay::FrameStepper turned(shortSceneCamera().forImageSize(srcB.size()), b, shortSceneOptions());
  turned.setUserRotation(turn);
  EXPECT_TRUE(turned.userRotation().isApprox(turn));
  cv::Mat ia, ib;
  int compared = 0, posedTools = 0;
  while (srcA.read(ia) && srcB.read(ib)) {
    const auto ra = plain.step(ia, srcA.index(), srcA.index() / srcA.fps());
    const auto rb = turned.step(ib, srcB.index(), srcB.index() / srcB.fps());
    ASSERT_EQ(ra.planetInCamera.has_value(), rb.planetInCamera.has_value());
    if (ra.planetInCamera) {
      // The turned planet's frame: camera-from-turned = camera-from-planet * turn.
      EXPECT_TRUE(rb.planetInCamera->R.isApprox(ra.planetInCamera->R * turn, 1e-12));
      EXPECT_TRUE(rb.planetInCamera->t.isApprox(ra.planetInCamera->t, 1e-12));
    }
    if (ra.scene.tipValid) {
      // The tip in the turned planet's coordinates: the same point in the camera.
      EXPECT_TRUE(rb.scene.tipPlanet.isApprox(turn.transpose() * ra.scene.tipPlanet, 1e-9));
      if (rb.planetInCamera) {
        EXPECT_TRUE(rb.planetInCamera->apply(rb.scene.tipPlanet)
                        .isApprox(ra.planetInCamera->apply(ra.scene.tipPlanet), 1e-9));
      }
      ++compared;
    }
    // The tool's shape (what hides the planet in the AR view): posed while both have a pose,
    // the same points in the camera for the turned planet, its stick ending at the tip.
    ASSERT_EQ(ra.toolTriangles.size(), rb.toolTriangles.size());
    EXPECT_EQ(!ra.toolTriangles.empty(), ra.planetInCamera && ra.scene.tool.usable());
    for (std::size_t i = 0; i < ra.toolTriangles.size(); ++i)
      EXPECT_TRUE(
          rb.planetInCamera->apply(rb.toolTriangles[i] / turned.scale())
              .isApprox(ra.planetInCamera->apply(ra.toolTriangles[i] / plain.scale()), 1e-9));
    if (!ra.toolTriangles.empty() && ra.scene.tipValid) {
      double nearest = 1e300;
      for (const auto& p : ra.toolTriangles)
        nearest = std::min(nearest, (p - plain.scale() * ra.scene.tipPlanet).norm());
      EXPECT_LT(nearest, 1e-9 * plain.scale());
      ++posedTools;
    }
  }
  EXPECT_GE(compared, 10);
  EXPECT_GE(posedTools, 10);
  // Not a rotation: refused, nothing changed.
  EXPECT_THROW(turned.setUserRotation(2 * Eigen::Matrix3d::Identity()), core::InputError);
  EXPECT_TRUE(turned.userRotation().isApprox(turn));
}

TEST(ReplayStepper, ToolAndBrushChangeBetweenFramesAndBadValuesAreRefused) {
  auto planet = testkit::bumpyTerrain(7, 4, 3000.0);
  tracking::FrameSource src(shortSceneVideo());
  replay::FrameStepper stepper(shortSceneCamera().forImageSize(src.size()), planet,
                               shortSceneOptions());
  edit::BrushSettings brush = stepper.options().brush;
  brush.radius *= 2;
  stepper.setBrush(brush);
  EXPECT_DOUBLE_EQ(stepper.toolRadius(), brush.radius);
  stepper.setTool(replay::ReplayTool::kDisplace);
  EXPECT_DOUBLE_EQ(stepper.toolRadius(), stepper.options().displace.radius);
  brush.radius = -1;
  EXPECT_THROW(stepper.setBrush(brush), core::InputError);
  EXPECT_EQ(stepper.options().tool, replay::ReplayTool::kDisplace);
  EXPECT_GT(stepper.options().brush.radius, 0);
  cv::Mat image;
  while (src.read(image)) stepper.step(image, src.index(), src.index() / src.fps());
  EXPECT_EQ(stepper.summary().frames, 12);
}

TEST(ReplayStepper, TheSandTinToolSculptsTheSameWayTwiceAndKeepsTheVolume) {
  // A 257^2 planet (156 km cells): the 400 km stamp is 2.6 cells across its radius.
  const auto run = [](int& applied) {
    auto planet = testkit::bumpyTerrain(8, 4, 3000.0);
    const sand::SandGrid grid(planet.chartPtr());
    const double v0 = grid.volume(planet.heights());
    auto o = shortSceneOptions();
    o.tool = replay::ReplayTool::kTinSand;
    tracking::FrameSource src(shortSceneVideo());
    replay::FrameStepper stepper(shortSceneCamera().forImageSize(src.size()), planet, o);
    cv::Mat image;
    applied = 0;
    while (src.read(image))
      applied += stepper.step(image, src.index(), src.index() / src.fps()).touching;
    EXPECT_LE(std::abs(grid.volume(planet.heights()) - v0) / grid.absVolume(planet.heights()),
              1e-9);
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(planet));
    return std::vector<float>(planet.heights().begin(), planet.heights().end());
  };
  int touchedA = 0, touchedB = 0;
  const auto a = run(touchedA), b = run(touchedB);
  EXPECT_GT(touchedA, 0) << "the short scene's tool touches the planet";
  EXPECT_EQ(touchedA, touchedB);
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
  const auto fresh = testkit::bumpyTerrain(8, 4, 3000.0);
  EXPECT_NE(0, std::memcmp(a.data(), fresh.heights().data(), a.size() * sizeof(float)))
      << "the stamps changed the planet";
}

TEST(ReplayStepper, PlanetScaledByHandIsThePlanetConfiguredAtThatSize) {
  // A stepper whose planet is scaled by hand before the first frame replays exactly as one
  // configured with that size; bad sizes are refused and change nothing.
  const auto sized = [] {
    auto o = shortSceneOptions();
    o.scene.planetRadius *= 1.5;
    return o;
  }();
  auto a = testkit::bumpyTerrain(7, 4, 3000.0);
  auto b = testkit::bumpyTerrain(7, 4, 3000.0);
  tracking::FrameSource srcA(shortSceneVideo()), srcB(shortSceneVideo());
  const auto camera = shortSceneCamera().forImageSize(srcA.size());
  replay::FrameStepper configured(camera, a, sized);
  replay::FrameStepper scaled(camera, b, shortSceneOptions());
  const double before = scaled.scale();
  for (double bad : {0.0, -0.1, std::nan(""), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(scaled.setPlanetSize(bad), core::InputError) << bad;
    EXPECT_EQ(scaled.scale(), before);
  }
  scaled.setPlanetSize(sized.scene.planetRadius);
  EXPECT_DOUBLE_EQ(scaled.scale(), configured.scale());
  EXPECT_NEAR(scaled.scale(), before / 1.5, 1e-9 * before);
  cv::Mat image;
  int touching = 0;
  while (srcA.read(image)) {
    const auto ra = configured.step(image, srcA.index(), srcA.index() / srcA.fps());
    ASSERT_TRUE(srcB.read(image));
    const auto rb = scaled.step(image, srcB.index(), srcB.index() / srcB.fps());
    EXPECT_EQ(ra.logLine, rb.logLine);
    touching += ra.touching;
  }
  configured.endStroke();
  scaled.endStroke();
  EXPECT_GT(touching, 0);
  EXPECT_TRUE(
      std::memcmp(a.heights().data(), b.heights().data(), a.heights().size() * sizeof(float)) == 0);
}

// The view draws the TIN tool's region TIN (FrameStepper::viewPatch) from its first stamp,
// through the stroke and after it, until the grid under it changes: an undo hides it, a redo
// back to the same floats shows it again, another tool ends it.
TEST(ReplayStepper, TheViewDrawsTheStrokeTinUntilTheGridUnderItChanges) {
  auto planet = testkit::bumpyTerrain(8, 4, 3000.0);
  auto o = shortSceneOptions();
  o.tool = replay::ReplayTool::kTinSand;
  o.undo = true;
  tracking::FrameSource src(shortSceneVideo());
  replay::FrameStepper stepper(shortSceneCamera().forImageSize(src.size()), planet, o);
  EXPECT_EQ(stepper.viewPatch(), nullptr) << "no stamp yet";
  cv::Mat image;
  bool stamped = false;
  std::shared_ptr<const terrain::MeshPatch> patch;
  while (src.read(image)) {
    stamped |= stepper.step(image, src.index(), src.index() / src.fps()).touching;
    if (stamped) {
      patch = stepper.viewPatch();
      ASSERT_NE(patch, nullptr) << "frame " << src.index() << ": stamped, and no region drawn";
    }
  }
  ASSERT_TRUE(stamped);
  stepper.endStroke();
  EXPECT_EQ(stepper.viewPatch(), patch) << "the stroke's end changes nothing on screen";
  EXPECT_GT(patch->replaces.size(), 0u);
  EXPECT_EQ(patch->heights.size(), patch->positions.size());
  stepper.pipeline().undo();
  EXPECT_EQ(stepper.viewPatch(), nullptr) << "the grid no longer holds what the region wrote";
  stepper.pipeline().redo();
  const auto again = stepper.viewPatch();
  ASSERT_NE(again, nullptr) << "a redo brings back the floats the region wrote";
  EXPECT_EQ(again->positions, patch->positions);
  stepper.setTool(replay::ReplayTool::kBrush);
  EXPECT_EQ(stepper.viewPatch(), nullptr);
  stepper.setTool(replay::ReplayTool::kTinSand);
  EXPECT_EQ(stepper.viewPatch(), nullptr) << "the tool is made afresh, with no region";
}
