// Synthetic video (lossless FFV1, bit-exact read-back), replay determinism, bad input.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/input_error.hpp"
#include "error_of.hpp"
#include "fresh_dir.hpp"
#include "replay/replay.hpp"
#include "short_scene.hpp"
#include "test_terrains.hpp"
#include "tracking/synth.hpp"
#include "tracking/video.hpp"

using namespace ps;
using testkit::errorOf;

TEST(TrackingSynth, RenderingIsDeterministicAndFfv1IsLossless) {
  auto script = tracking::builtinScene("short");
  script.colour = false;
  const tracking::SynthRenderer a(script), b(script);
  EXPECT_EQ(cv::norm(a.render(5), b.render(5), cv::NORM_INF), 0.0);
  tracking::FrameSource src(testkit::shortSceneVideo());
  EXPECT_EQ(src.size(), script.size);
  cv::Mat frame;
  int n = 0;
  while (src.read(frame)) {
    cv::Mat grey = frame;
    if (frame.channels() == 3) cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    EXPECT_EQ(cv::norm(grey, a.render(n), cv::NORM_INF), 0.0) << "frame " << n;
    ++n;
  }
  EXPECT_EQ(n, script.frames());
  EXPECT_FALSE(src.truncated());
  // Ground truth: the tip comes down (smoothstep) from 10 mm at frame 0 to 1 mm inside at frame
  // 3: 7.2 mm at frame 1, 1.9 mm at frame 2.
  EXPECT_NEAR(a.truth(1).tipHeight, 0.010 - 0.011 * (7.0 / 27), 1e-9);
  EXPECT_NEAR(a.truth(2).tipHeight, 0.010 - 0.011 * (20.0 / 27), 1e-9);
  EXPECT_NEAR(a.truth(5).tipHeight, -0.001, 1e-9);
  // The tool marker is in full view; the tool card covers part of the planet marker's quiet
  // zone (visible in the rendered frame), which the ground truth reports as occluded.
  EXPECT_TRUE(a.truth(5).toolVisible);
  EXPECT_TRUE(a.truth(5).planetOccluded);
  EXPECT_FALSE(a.truth(5).planetVisible);
}

// The `near` scene exists to measure tracking with the camera 0.30-0.33 m from the planet: it
// is only useful if both markers are in full view there, touching, in enough frames.
TEST(TrackingSynth, NearSceneHasBothMarkersInViewAtAThirdOfAMetre) {
  const tracking::SynthRenderer r(tracking::builtinScene("near"));
  int both = 0, bothTouching = 0;
  double nearest = 1e9, farthest = 0;
  for (int f = 0; f < r.frames(); ++f) {
    const tracking::FrameTruth t = r.truth(f);
    if (!t.planetVisible || !t.toolVisible) continue;
    ++both;
    bothTouching += t.tipHeight <= 0.004 ? 1 : 0;  // the default touch distance
    // The camera's distance from the planet's centre (6 cm above the marker's origin).
    const double d = (t.camera.inverse().apply(Eigen::Vector3d::Zero()) -
                      Eigen::Vector3d(0, 0, r.script().planetRadius))
                         .norm();
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  EXPECT_GE(both, 80);
  EXPECT_GE(bothTouching, 75);
  EXPECT_NEAR(nearest, 0.30, 1e-6);
  EXPECT_LE(farthest, 0.33 + 1e-6);
}

TEST(TrackingReplay, TwoReplaysAreBitIdenticalAndSculpt) {
  std::string logs[2];
  std::vector<float> heights[2];
  replay::ReplaySummary s;
  for (int run = 0; run < 2; ++run) {
    auto planet = testkit::bumpyTerrain(7, 4, 3000.0);
    tracking::FrameSource src(testkit::shortSceneVideo());
    std::ostringstream log;
    s = replay::runReplay(src, testkit::shortSceneCamera(), planet, testkit::shortSceneOptions(),
                          log);
    logs[run] = log.str();
    heights[run].assign(planet.heights().begin(), planet.heights().end());
  }
  EXPECT_EQ(logs[0], logs[1]);
  EXPECT_EQ(std::memcmp(heights[0].data(), heights[1].data(), heights[0].size() * sizeof(float)),
            0);
  EXPECT_EQ(s.frames, 12);
  EXPECT_GE(s.framesWithTip, 10);
  EXPECT_GE(s.touchingFrames, 4);
  EXPECT_GE(s.strokes, 1);
  EXPECT_GT(s.modifiedVertices, 0u);
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_NE(logs[0].find("\"stroke\":\"begin\""), std::string::npos);
}

TEST(TrackingReplay, BadInputIsNamedAndPartialVideosReplayWhatTheyHold) {
  const auto dir = testkit::freshDir("tracking_replay");
  EXPECT_NE(
      errorOf([&] { tracking::FrameSource s(dir / "nope.mkv"); }).find("nope.mkv: no such file"),
      std::string::npos);
  std::ofstream(dir / "empty.mkv").close();
  EXPECT_NE(errorOf([&] {
              tracking::FrameSource s(dir / "empty.mkv");
            }).find("empty.mkv: the file is empty"),
            std::string::npos);
  std::ofstream(dir / "junk.mkv") << "this is not a video at all";
  EXPECT_NE(errorOf([&] { tracking::FrameSource s(dir / "junk.mkv"); }).find("junk.mkv"),
            std::string::npos);
  // A video cut in the middle: replays the frames that decode and says it was cut.
  {
    std::ifstream in(testkit::shortSceneVideo(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(dir / "cut.mkv", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  try {
    tracking::FrameSource src(dir / "cut.mkv");
    auto planet = testkit::bumpyTerrain(6, 4, 3000.0);
    std::ostringstream log;
    const auto s = replay::runReplay(src, testkit::shortSceneCamera(), planet,
                                     testkit::shortSceneOptions(), log);
    EXPECT_LT(s.frames, 12);
    EXPECT_GT(s.frames, 0);
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.mkv"), std::string::npos);  // refused, named
  }
  // No marker ever seen (a blank video): a warning, nothing sculpted.
  {
    tracking::LosslessWriter w(dir / "blank.mkv", {160, 120}, 30, false);
    for (int i = 0; i < 3; ++i) w.write(cv::Mat(120, 160, CV_8U, cv::Scalar(128)));
    w.close();
    tracking::FrameSource src(dir / "blank.mkv");
    auto planet = testkit::bumpyTerrain(6, 4, 3000.0);
    std::ostringstream log;
    const auto s = replay::runReplay(src, tracking::SynthScript::syntheticCamera({160, 120}),
                                     planet, testkit::shortSceneOptions(), log);
    EXPECT_EQ(s.frames, 3);
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_NE(s.warnings[0].find("was ever seen"), std::string::npos);
  }
  // A calibration for another aspect ratio.
  {
    tracking::FrameSource src(testkit::shortSceneVideo());
    auto planet = testkit::bumpyTerrain(6, 4, 3000.0);
    std::ostringstream log;
    auto calib = tracking::SynthScript::syntheticCamera({640, 360});
    calib.source = "wide.yml";
    EXPECT_NE(errorOf([&] {
                replay::runReplay(src, calib, planet, testkit::shortSceneOptions(), log);
              }).find("wide.yml: calibrated for 640x360"),
              std::string::npos);
  }
  std::filesystem::remove_all(dir);
}
