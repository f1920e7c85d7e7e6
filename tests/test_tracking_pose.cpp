// Calibration files, marker poses (IPPE candidates, ambiguity), One Euro filters, hold-then-lost,
// the scene (planet on its marker, tool tip, touching).
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>

#include "app/build_paths.hpp"
#include "core/input_error.hpp"
#include "error_of.hpp"
#include "fresh_dir.hpp"
#include "tracking/calibration.hpp"
#include "tracking/filter.hpp"
#include "tracking/pose.hpp"
#include "tracking/tracker.hpp"

using namespace ps;
using testkit::errorOf;
using tracking::CameraCalibration;
using tracking::Pose;

namespace {

using testkit::writeText;

const std::string kK =
    "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
    "   data: [ 500., 0., 319.5, 0., 510., 239.5, 0., 0., 1. ]\n";

Pose poseFrom(double rx, double ry, double rz, double x, double y, double z) {
  return Pose::fromRvecTvec({rx, ry, rz}, {x, y, z});
}

tracking::Detection detectionOf(const Pose& p, double size, const CameraCalibration& c, int id) {
  tracking::Detection d;
  d.id = id;
  d.corners = tracking::projectMarker(p, size, c);
  return d;
}

}  // namespace

TEST(TrackingCalibration, ReadsBothDistortionShapesAndMissingSizes) {
  const auto dir = testkit::freshDir("tracking_pose");
  writeText(dir / "a.yml", "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n" + kK +
                               "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n"
                               "   dt: d\n   data: [ 0.1, -0.2, 0.001, 0.002, 0.05 ]\n");
  writeText(dir / "b.yml", "%YAML:1.0\n---\n" + kK +
                               "distortion_coefficients: !!opencv-matrix\n   rows: 5\n   cols: 1\n"
                               "   dt: d\n   data: [ 0.1, -0.2, 0.001, 0.002, 0.05 ]\n");
  const auto a = tracking::loadCalibration(dir / "a.yml");
  const auto b = tracking::loadCalibration(dir / "b.yml");
  EXPECT_EQ(a.imageSize, cv::Size(640, 480));
  EXPECT_EQ(b.imageSize, cv::Size(0, 0));
  EXPECT_EQ(cv::norm(a.distortion, b.distortion, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.distortion.rows, 1);
  EXPECT_EQ(a.K(1, 1), 510.0);
  // Unknown size: taken as the video's.
  EXPECT_EQ(b.forImageSize({800, 600}).imageSize, cv::Size(800, 600));
  EXPECT_EQ(b.forImageSize({800, 600}).K(0, 0), 500.0);
  // Rescaled with the pixel-centre convention.
  const auto big = a.forImageSize({1280, 960});
  EXPECT_DOUBLE_EQ(big.K(0, 0), 1000.0);
  EXPECT_DOUBLE_EQ(big.K(1, 1), 1020.0);
  EXPECT_DOUBLE_EQ(big.K(0, 2), 639.5);
  EXPECT_DOUBLE_EQ(big.K(1, 2), 479.5);
  EXPECT_NE(errorOf([&] {
              a.forImageSize({1280, 720});
            }).find("a.yml: calibrated for 640x480"),
            std::string::npos);
  // Round trip.
  tracking::saveCalibration(a, dir / "c.yml", "test");
  const auto c = tracking::loadCalibration(dir / "c.yml");
  EXPECT_EQ(cv::norm(cv::Mat(c.K), cv::Mat(a.K), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(c.distortion, a.distortion, cv::NORM_INF), 0.0);
  EXPECT_EQ(c.imageSize, a.imageSize);
  std::filesystem::remove_all(dir);
}

TEST(TrackingCalibration, BadFilesNameTheFile) {
  const auto dir = testkit::freshDir("tracking_pose");
  const std::string d5 =
      "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
      "   data: [ 0., 0., 0., 0., 0. ]\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"%YAML:1.0\n---\n" + d5, "no camera_matrix"},
      {"%YAML:1.0\n---\n" + kK, "no distortion_coefficients"},
      {"%YAML:1.0\n---\n" + kK +
           "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 3\n   dt: d\n"
           "   data: [ 0., 0., 0. ]\n",
       "distortion_coefficients must be 1xN or Nx1"},
      {"%YAML:1.0\n---\nimage_width: 640\n" + kK + d5, "image_width and image_height"},
      {"%YAML:1.0\n---\ncamera_matrix: [1, 2\n", "bad.yml"},
      {"%YAML:1.0\n---\n" +
           std::string("camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n"
                       "   dt: d\n   data: [ -5., 0., 1., 0., 5., 1., 0., 0., 1. ]\n") +
           d5,
       "focal lengths"},
      {"", "bad.yml"},
  };
  for (const auto& [text, expect] : cases) {
    writeText(dir / "bad.yml", text);
    const std::string e = errorOf([&] { tracking::loadCalibration(dir / "bad.yml"); });
    EXPECT_NE(e.find("bad.yml"), std::string::npos) << e;
    EXPECT_NE(e.find(expect), std::string::npos) << "got: " << e << "\nexpected: " << expect;
  }
  EXPECT_NE(errorOf([&] {
              tracking::loadCalibration(dir / "missing.yml");
            }).find("missing.yml: cannot open"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(TrackingCalibration, ShippedFilesLoad) {
  for (const char* f : {"calib/webcam-640x480.yml", "calib/synthetic-640x480.yml"}) {
    const auto c = tracking::loadCalibration(ps::app::sourceDir() / f);
    EXPECT_EQ(c.imageSize, cv::Size(640, 480)) << f;
  }
  const auto shared = ps::app::sharedDir() / "data/real-markers/tutorial_camera_charuco.yml";
  if (std::filesystem::exists(shared)) {
    EXPECT_NEAR(tracking::loadCalibration(shared).K(0, 0), 452.5, 0.1);
  }
}

TEST(TrackingPose, RecoversPosesAndKeepsBothCandidates) {
  const auto cam = CameraCalibration::pinhole(600, 600, 319.5, 239.5, {640, 480});
  for (const Pose& truth :
       {poseFrom(2.6, 0.2, 0.1, 0.03, -0.02, 0.5), poseFrom(0.3, 2.9, -0.4, -0.1, 0.05, 0.8),
        poseFrom(M_PI, 0, 0, 0, 0, 0.3)}) {
    const auto c = tracking::solveMarkerPose(tracking::projectMarker(truth, 0.05, cam), 0.05, cam);
    ASSERT_GE(c.count, 1);
    EXPECT_LT((c.poses[0].t - truth.t).norm(), 1e-6);
    EXPECT_LT(tracking::rotationAngle(c.poses[0].R, truth.R), 1e-6);
    EXPECT_LT(c.rms[0], 1e-6);
  }
  // NaN corners: no pose, no exception.
  std::array<cv::Point2d, 4> bad{};
  bad[0].x = std::nan("");
  EXPECT_EQ(tracking::solveMarkerPose(bad, 0.05, cam).count, 0);
}

TEST(TrackingPose, AmbiguityGoesToContinuityWhenTheRatioIsSmall) {
  tracking::PoseCandidates c;
  c.count = 2;
  c.poses[0] = poseFrom(M_PI, 0.0, 0, 0, 0, 0.6);
  c.poses[1] = poseFrom(M_PI, 0.4, 0, 0, 0, 0.6);
  c.rms = {0.10, 0.12};
  const Pose previous = poseFrom(M_PI, 0.38, 0, 0, 0, 0.6);
  auto ch = tracking::choosePose(c, &previous, 4.0);
  EXPECT_TRUE(ch.byContinuity);
  EXPECT_EQ(ch.candidate, 1);
  EXPECT_EQ(tracking::choosePose(c, nullptr, 4.0).candidate, 0);  // nothing to continue from
  c.rms = {0.10, 0.9};                                            // clearly better: error decides
  EXPECT_EQ(tracking::choosePose(c, &previous, 4.0).candidate, 0);
}

TEST(TrackingFilter, OneEuroSmoothsAtRestAndFollowsMotion) {
  tracking::OneEuroVector f({1.0, 50.0, 1.0});
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1e-3);
  double rawJitter = 0, filteredJitter = 0;
  Eigen::Vector3d prevRaw, prevF;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d raw(noise(rng), noise(rng), 0.5 + noise(rng));
    const Eigen::Vector3d out = f.filter(raw, 1 / 30.0);
    if (i > 30) {
      rawJitter += (raw - prevRaw).norm();
      filteredJitter += (out - prevF).norm();
    }
    prevRaw = raw, prevF = out;
  }
  EXPECT_LT(filteredJitter, 0.4 * rawJitter);
  // A steady motion at 0.2 m/s: the lag stays within a couple of millimetres.
  tracking::OneEuroVector g({1.0, 400.0, 1.0});
  double lag = 0;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d x(0.2 * i / 30.0, 0, 0.5);
    lag = (g.filter(x, 1 / 30.0) - x).norm();
  }
  EXPECT_LT(lag, 2e-3);
  // Rotation filter: constant input comes out unchanged and unit length.
  tracking::OneEuroRotation r;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  Eigen::Quaterniond out;
  for (int i = 0; i < 10; ++i) out = r.filter(q, 1 / 30.0);
  EXPECT_LT(out.angularDistance(q), 1e-9);
}

TEST(TrackingScene, TipInThePlanetFrameHoldThenLost) {
  const auto cam = CameraCalibration::pinhole(600, 600, 319.5, 239.5, {640, 480});
  tracking::SceneConfig sc;
  sc.planet.filter = sc.tool.filter = sc.filterTip = false;
  sc.planet.holdSeconds = sc.tool.holdSeconds = 0.1;
  // The tool's stick lies over the planet marker's edge here: its exact corners are used anyway
  // (a camera's would be dragged; TrackingOcclusion.APlanetMarkerUnderTheTool...).
  sc.toolCoverBandCells = 0;
  tracking::SceneTracker scene(sc);
  // Planet marker flat in front of the camera (its normal toward the camera: a half turn about
  // x), tool beside it, tip offset (0, -0.08, 0) -> (0, +0.08, 0) in the camera frame.
  const Pose planet = poseFrom(M_PI, 0, 0, 0, 0, 0.6);
  const Pose tool = poseFrom(M_PI, 0, 0, 0.02, -0.11, 0.6 - 0.06);
  const std::vector<tracking::Detection> both = {detectionOf(planet, sc.planet.size, cam, 0),
                                                 detectionOf(tool, sc.tool.size, cam, 1)};
  auto f = scene.update(both, cam, 0, 0.0);
  ASSERT_TRUE(f.tipValid);
  // Planet centre = planet marker + 0.06 along its normal: (0, 0, 0.54) in the camera frame;
  // tip = (0.02, -0.03, 0.54) in the camera frame = (0.02, 0.03, 0) in the planet frame.
  EXPECT_LT((f.tipPlanet - Eigen::Vector3d(0.02, 0.03, 0.0)).norm(), 1e-6);
  EXPECT_NEAR(f.tipHeight, std::hypot(0.02, 0.03) - 0.06, 1e-6);
  EXPECT_TRUE(f.touching);
  // Tool not seen: held within the hold time, then lost.
  const std::vector<tracking::Detection> planetOnly = {both[0]};
  f = scene.update(planetOnly, cam, 1, 1 / 30.0);
  EXPECT_EQ(f.tool.state, tracking::TrackState::kHeld);
  EXPECT_TRUE(f.tipValid);
  EXPECT_TRUE(f.tipHeld);
  f = scene.update(planetOnly, cam, 4, 4 / 30.0);
  EXPECT_EQ(f.tool.state, tracking::TrackState::kLost);
  EXPECT_FALSE(f.tipValid);
  // The same id twice with no last pose: neither is used, and the note says so.
  tracking::SceneTracker fresh(sc);
  const std::vector<tracking::Detection> twice = {
      both[0], both[1], detectionOf(poseFrom(0, 0, 0, -0.1, 0, 0.7), 0.05, cam, 1)};
  f = fresh.update(twice, cam, 0, 0.0);
  EXPECT_EQ(f.tool.state, tracking::TrackState::kLost);
  ASSERT_FALSE(f.notes.empty());
  EXPECT_NE(f.notes[0].find("seen 2 times"), std::string::npos);
  // With a last pose, the one nearest it wins.
  fresh.update(both, cam, 1, 1 / 30.0);
  f = fresh.update(twice, cam, 2, 2 / 30.0);
  EXPECT_EQ(f.tool.state, tracking::TrackState::kTracked);
  EXPECT_LT((f.tool.pose.t - tool.t).norm(), 1e-6);
  // Bad configurations are refused with the field named.
  sc.tool.id = 0;
  EXPECT_NE(errorOf([&] { tracking::SceneTracker s(sc); }).find("same id 0"), std::string::npos);
}
