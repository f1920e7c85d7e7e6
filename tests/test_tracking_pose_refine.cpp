// The marker sets' pose polish (tracking/pose_refine.hpp) against OpenCV's Levenberg-Marquardt,
// which it replaces there: the same minimum on random bodies, lenses and noise.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <random>

#include "tracking/calibration.hpp"
#include "tracking/pose_refine.hpp"

using namespace ps;
using tracking::CameraCalibration;
using tracking::Pose;

namespace {

struct Problem {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  Pose truth;
};

// A body of `markers` squares (40 mm) spread over a 0.2 m board, or folded onto a cube's faces
// when `solid`, seen 0.3-0.8 m away turned up to 50 degrees, corners with Gaussian noise.
Problem randomProblem(std::mt19937& rng, const CameraCalibration& cam, int markers, bool solid,
                      double noisePx) {
  std::uniform_real_distribution<double> u(-1, 1);
  Problem p;
  for (int m = 0; m < markers; ++m) {
    const Eigen::Vector3d centre(0.08 * u(rng), 0.08 * u(rng), solid ? 0.04 * u(rng) : 0.0);
    const Eigen::Matrix3d turn =
        solid
            ? Eigen::AngleAxisd(0.8 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
                  .toRotationMatrix()
            : Eigen::Matrix3d::Identity();
    for (const auto& c : {Eigen::Vector3d(-0.02, 0.02, 0), Eigen::Vector3d(0.02, 0.02, 0),
                          Eigen::Vector3d(0.02, -0.02, 0), Eigen::Vector3d(-0.02, -0.02, 0)}) {
      const Eigen::Vector3d x = centre + turn * c;
      p.object.emplace_back(x.x(), x.y(), x.z());
    }
  }
  const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng)).normalized();
  p.truth.R = Eigen::AngleAxisd(M_PI + 0.85 * u(rng), Eigen::Vector3d::UnitX()).toRotationMatrix() *
              Eigen::AngleAxisd(0.4 * u(rng), axis).toRotationMatrix();
  p.truth.t = Eigen::Vector3d(0.05 * u(rng), 0.05 * u(rng), 0.55 + 0.25 * u(rng));
  const Eigen::Vector3d rv = p.truth.rvec();
  cv::projectPoints(p.object, cv::Vec3d(rv.x(), rv.y(), rv.z()),
                    cv::Vec3d(p.truth.t.x(), p.truth.t.y(), p.truth.t.z()), cv::Mat(cam.K),
                    cam.distortion, p.image);
  std::normal_distribution<double> noise(0, noisePx);
  for (auto& q : p.image) q += cv::Point2d(noise(rng), noise(rng));
  return p;
}

Pose perturbed(const Pose& p, std::mt19937& rng, double angle, double shift) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
  return {Eigen::AngleAxisd(angle, axis).toRotationMatrix() * p.R,
          p.t + shift * Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized()};
}

double openCvRefine(const Problem& p, const CameraCalibration& cam, Pose& pose) {
  const Eigen::Vector3d r0 = pose.rvec();
  cv::Mat rv = (cv::Mat_<double>(3, 1) << r0.x(), r0.y(), r0.z());
  cv::Mat tv = (cv::Mat_<double>(3, 1) << pose.t.x(), pose.t.y(), pose.t.z());
  cv::solvePnPRefineLM(p.object, p.image, cv::Mat(cam.K), cam.distortion, rv, tv);
  std::vector<cv::Point2d> px;
  cv::projectPoints(p.object, rv, tv, cv::Mat(cam.K), cam.distortion, px);
  double sum = 0;
  for (std::size_t i = 0; i < px.size(); ++i) sum += (px[i] - p.image[i]).dot(px[i] - p.image[i]);
  pose = Pose::fromRvecTvec({rv.at<double>(0), rv.at<double>(1), rv.at<double>(2)},
                            {tv.at<double>(0), tv.at<double>(1), tv.at<double>(2)});
  return std::sqrt(sum / double(px.size()));
}

CameraCalibration lens(int coefficients) {
  CameraCalibration c = CameraCalibration::pinhole(610, 605, 322.5, 236.5, {640, 480});
  const double k[14] = {-0.21, 0.09,   0.0011,  -0.0007, -0.02,  0.05, -0.01,
                        0.004, 0.0015, -0.0004, 0.0009,  0.0002, 0.01, -0.008};
  c.distortion = cv::Mat(1, coefficients, CV_64F);
  for (int i = 0; i < coefficients; ++i) c.distortion.at<double>(i) = k[i];
  return c;
}

}  // namespace

TEST(TrackingPoseRefine, ReachesOpenCvsMinimumOnRandomBodiesAndLenses) {
  std::mt19937 rng(2411);
  int cases = 0;
  for (int coefficients : {0, 4, 5, 8}) {
    const CameraCalibration cam = lens(coefficients);
    for (int trial = 0; trial < 60; ++trial) {
      const bool solid = trial % 2 == 1;
      const int markers = 1 + trial % 9;
      const Problem p = randomProblem(rng, cam, markers, solid, trial % 3 == 0 ? 0.0 : 0.3);
      const Pose seed = perturbed(p.truth, rng, 0.05, 0.01);  // 2.9 degrees, 10 mm
      Pose ours = seed, theirs = seed;
      const double e = tracking::refinePose(p.object, p.image, cam, ours);
      const double eRef = openCvRefine(p, cam, theirs);
      ASSERT_TRUE(std::isfinite(e));
      // Never worse than OpenCV's answer, and the same pose: OpenCV stops at a relative step
      // of FLT_EPSILON, so its pose may sit 1e-6 from the exact minimum.
      EXPECT_LE(e, eRef * (1 + 1e-9) + 1e-12) << coefficients << " coefficients, trial " << trial;
      EXPECT_LT(tracking::rotationAngle(ours.R, theirs.R), 2e-5) << trial;
      EXPECT_LT((ours.t - theirs.t).norm(), 2e-6) << trial;
      if (trial % 3 == 0) {
        // Exact corners: the truth itself, to rounding.
        EXPECT_LT(e, 1e-8) << trial;
        EXPECT_LT(tracking::rotationAngle(ours.R, p.truth.R), 1e-10) << trial;
        EXPECT_LT((ours.t - p.truth.t).norm(), 1e-11) << trial;
      }
      ++cases;
    }
  }
  EXPECT_EQ(cases, 240);
}

TEST(TrackingPoseRefine, LensTermsItDoesNotModelGoToOpenCvsSolver) {
  // Thin-prism terms (coefficients 9-12): the answer is OpenCV's own, bit for bit.
  const CameraCalibration cam = lens(12);
  std::mt19937 rng(7);
  const Problem p = randomProblem(rng, cam, 6, false, 0.3);
  Pose ours = perturbed(p.truth, rng, 0.03, 0.005), theirs = ours;
  const double e = tracking::refinePose(p.object, p.image, cam, ours);
  const double eRef = openCvRefine(p, cam, theirs);
  EXPECT_EQ(e, eRef);
  EXPECT_EQ(ours.t, theirs.t);
  // With those terms zero, the model covers it and agrees with OpenCV.
  CameraCalibration zeroPrism = cam;
  for (int i = 8; i < 12; ++i) zeroPrism.distortion.at<double>(i) = 0;
  const Problem q = randomProblem(rng, zeroPrism, 6, false, 0.3);
  Pose a = perturbed(q.truth, rng, 0.03, 0.005), b = a;
  const double ea = tracking::refinePose(q.object, q.image, zeroPrism, a);
  EXPECT_LE(ea, openCvRefine(q, zeroPrism, b) * (1 + 1e-9));
  EXPECT_LT((a.t - b.t).norm(), 2e-6);
}

TEST(TrackingPoseRefine, RefusesWhatItCannotSolve) {
  const CameraCalibration cam = lens(5);
  std::mt19937 rng(99);
  Problem p = randomProblem(rng, cam, 3, true, 0.0);
  // A seed with the body behind the camera, mismatched sizes, no points, a non-finite seed.
  Pose behind = p.truth;
  behind.t.z() = -behind.t.z();
  EXPECT_EQ(tracking::refinePose(p.object, p.image, cam, behind),
            std::numeric_limits<double>::infinity());
  Pose seed = p.truth;
  std::vector<cv::Point2d> fewer(p.image.begin(), p.image.end() - 1);
  EXPECT_EQ(tracking::refinePose(p.object, fewer, cam, seed),
            std::numeric_limits<double>::infinity());
  EXPECT_EQ(tracking::refinePose({}, {}, cam, seed), std::numeric_limits<double>::infinity());
  Pose nan = p.truth;
  nan.t.x() = std::nan("");
  EXPECT_EQ(tracking::refinePose(p.object, p.image, cam, nan),
            std::numeric_limits<double>::infinity());
  // Corners that are not numbers.
  p.image[2].x = std::nan("");
  seed = p.truth;
  EXPECT_EQ(tracking::refinePose(p.object, p.image, cam, seed),
            std::numeric_limits<double>::infinity());
}
