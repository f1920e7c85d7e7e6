#pragma once
// Views of a printed calibration board (a ChArUco board, a chessboard) through a known camera
// with distortion, rendered exactly: the calibration tests' ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"
#include "tracking/charuco_calibration.hpp"
#include "tracking/chessboard_calibration.hpp"

namespace ps::testkit {

inline constexpr double kPixelsPerMetre = 6000;  // texture of the board: 0.17 mm per pixel
inline constexpr int kMargin = 120;              // white paper around the board (texture pixels)
inline const cv::TermCriteria kExact(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12);

// The true camera of the synthetic views: off-centre principal point, barrel distortion.
struct TrueCamera {
  cv::Size size{640, 480};
  cv::Matx33d K{610, 0, 323.5, 0, 604, 236.25, 0, 0, 1};
  cv::Mat dist = (cv::Mat_<double>(1, 5) << -0.12, 0.06, 0.0008, -0.0006, 0.0);
};

inline cv::Matx33d rotation(double ax, double ay, double az) {
  cv::Matx33d R;
  cv::Rodrigues(cv::Vec3d(ax, 0, 0), R);
  cv::Matx33d Ry, Rz;
  cv::Rodrigues(cv::Vec3d(0, ay, 0), Ry);
  cv::Rodrigues(cv::Vec3d(0, 0, az), Rz);
  // Untilted, the board faces the camera (board x right, y down, z away from the camera).
  return R * Ry * Rz;
}

// Renders views of a board through a camera with distortion: per output sample the ray is
// undistorted (once for all views), intersected with the board's plane and the board texture
// looked up; 3x3 samples per pixel, box filtered.
class ViewRenderer {
 public:
  ViewRenderer(const tracking::CharucoBoardSpec& spec, const TrueCamera& cam)
      : ViewRenderer(tracking::renderCharucoBoard(spec, kPixelsPerMetre, kMargin),
                     spec.squaresX * spec.squareLength, spec.squaresY * spec.squareLength, cam) {}
  ViewRenderer(const tracking::ChessboardSpec& spec, const TrueCamera& cam)
      : ViewRenderer(tracking::renderChessboard(spec, kPixelsPerMetre, kMargin),
                     spec.squaresX * spec.squareLength, spec.squaresY * spec.squareLength, cam) {}
  // A board's texture (kPixelsPerMetre, kMargin) of width x height metres.
  ViewRenderer(cv::Mat texture, double width, double height, const TrueCamera& cam)
      : width_(width), height_(height), cam_(cam), texture_(std::move(texture)) {
    const cv::Size big(cam.size.width * kSs, cam.size.height * kSs);
    std::vector<cv::Point2f> pixels;
    pixels.reserve(std::size_t(big.area()));
    for (int y = 0; y < big.height; ++y)
      for (int x = 0; x < big.width; ++x)
        pixels.emplace_back(float((x + 0.5) / kSs - 0.5), float((y + 0.5) / kSs - 0.5));
    // (The default 5 iterations leave tenths of a pixel at the corners of the image.)
    cv::undistortPoints(pixels, rays_, cam.K, cam.dist, cv::noArray(), cv::noArray(), kExact);
  }

  cv::Mat render(const cv::Matx33d& R, const cv::Vec3d& t, std::uint64_t seed) const {
    const cv::Size big(cam_.size.width * kSs, cam_.size.height * kSs);
    cv::Mat mapX(big, CV_32F), mapY(big, CV_32F);
    const cv::Matx33d Rt = R.t();
    const cv::Vec3d C = -(Rt * t);
    for (int y = 0; y < big.height; ++y)
      for (int x = 0; x < big.width; ++x) {
        const cv::Point2f& n = rays_[std::size_t(y * big.width + x)];
        const cv::Vec3d D = Rt * cv::Vec3d(n.x, n.y, 1.0);
        const double lambda = std::abs(D[2]) > 1e-12 ? -C[2] / D[2] : -1;
        float u = -1000, v = -1000;
        if (lambda > 0) {
          const cv::Vec3d P = C + lambda * D;
          u = float(kMargin + P[0] * kPixelsPerMetre - 0.5);
          v = float(kMargin + P[1] * kPixelsPerMetre - 0.5);
        }
        mapX.at<float>(y, x) = u;
        mapY.at<float>(y, x) = v;
      }
    cv::Mat sampled, image;
    cv::remap(texture_, sampled, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar(110));
    cv::resize(sampled, image, cam_.size, 0, 0, cv::INTER_AREA);
    // Paper is not pure white, ink not pure black; a little sensor noise.
    image.convertTo(image, CV_32F, 0.75, 30);
    cv::Mat noise(image.size(), CV_32F);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2.0);
    image += noise;
    image.convertTo(image, CV_8U);
    return image;
  }

  // Board pose with its centre at image pixel (px, py) at depth z, tilted by (ax, ay, az).
  cv::Mat view(double px, double py, double z, double ax, double ay, double az,
               std::uint64_t seed) const {
    const cv::Matx33d R = rotation(ax, ay, az);
    const cv::Vec3d centre(width_ / 2, height_ / 2, 0);
    // Aim the centre with the undistorted ray of that pixel.
    std::vector<cv::Point2d> p{{px, py}}, n;
    cv::undistortPoints(p, n, cam_.K, cam_.dist, cv::noArray(), cv::noArray(), kExact);
    const cv::Vec3d t = z * cv::Vec3d(n[0].x, n[0].y, 1.0) - R * centre;
    return render(R, t, seed);
  }

 private:
  static constexpr int kSs = 3;
  double width_, height_;
  TrueCamera cam_;
  cv::Mat texture_;
  std::vector<cv::Point2f> rays_;
};

inline double deg(double d) {
  return d * M_PI / 180;
}

// View i of the standard set: the board's centre on a 3x3 grid over the image and at its
// middle, tilted 20-40 degrees both ways, turned in its plane, at 0.40-0.55 m.
inline cv::Mat standardView(const ViewRenderer& r, int i) {
  const double xs[3] = {150, 320, 490}, ys[3] = {130, 240, 350};
  const double px = xs[i % 3], py = ys[(i / 3) % 3];
  const double sx = (i % 2 ? 1 : -1), sy = ((i / 2) % 2 ? 1 : -1);
  const double ax = sx * deg(25 + 5 * (i % 5)), ay = sy * deg(25 + 6 * (i % 4));
  const double az = deg(-30 + 13 * i % 60);
  const double z = 0.40 + 0.015 * (i % 11);
  return r.view(px, py, z, ax, ay, az, std::uint64_t(i + 1));
}

// A calibration of the synthetic views against the true camera: no problems, acceptable, RMS
// below maxRms; fx, fy, cx, cy within 3 px of the truth and within three of the standard
// deviations the solver reports (plus `slack` px), which are positive; k1 and the image size
// right. Call it inside ASSERT_NO_FATAL_FAILURE.
inline void expectTrueIntrinsics(const tracking::CalibrationResult& res, const TrueCamera& cam,
                                 double maxRms, double slack) {
  for (const auto& p : res.problems) ADD_FAILURE() << p;
  EXPECT_TRUE(res.acceptable);
  EXPECT_LT(res.rms, maxRms);
  const auto& K = res.calibration.K;
  ASSERT_GE(res.stdDeviations.size(), 4u);
  const double truth[4] = {cam.K(0, 0), cam.K(1, 1), cam.K(0, 2), cam.K(1, 2)};
  const double found[4] = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
  for (int i = 0; i < 4; ++i) {
    const double sd = res.stdDeviations[std::size_t(i)];
    EXPECT_NEAR(found[i], truth[i], 3.0) << "parameter " << i << " (fx, fy, cx, cy)";
    EXPECT_LE(std::abs(found[i] - truth[i]), 3 * sd + slack) << "parameter " << i;
    EXPECT_GT(sd, 0.0);
  }
  EXPECT_NEAR(res.calibration.distortion.at<double>(0), -0.12, 0.02);
  EXPECT_EQ(res.calibration.imageSize, cam.size);
}

// A calibration file written by the calibrate command from the synthetic views: fx, fy, cx, cy
// within 3 px of the true camera's, k1 within 0.02.
inline void expectNearTheTrueCamera(const tracking::CameraCalibration& c, const TrueCamera& cam) {
  EXPECT_NEAR(c.K(0, 0), cam.K(0, 0), 3.0);
  EXPECT_NEAR(c.K(1, 1), cam.K(1, 1), 3.0);
  EXPECT_NEAR(c.K(0, 2), cam.K(0, 2), 3.0);
  EXPECT_NEAR(c.K(1, 2), cam.K(1, 2), 3.0);
  EXPECT_NEAR(c.distortion.at<double>(0), -0.12, 0.02);
}

// View i (0-3) of four at the image's middle: too few views, covering too little.
inline cv::Mat middleView(const ViewRenderer& r, int i) {
  return r.view(320, 240, 0.5, deg(i % 2 ? 25 : -25), deg(i < 2 ? 20 : -20), 0,
                std::uint64_t(i + 1));
}

// The calibration of the four middle views: not acceptable, its problems naming the 4 views and
// the coverage.
inline void expectTooFewAndUncovered(const tracking::CalibrationResult& res) {
  EXPECT_FALSE(res.acceptable);
  bool views = false, coverage = false;
  for (const auto& p : res.problems) {
    views |= p.find("4 views") != std::string::npos;
    coverage |= p.find("covered") != std::string::npos;
  }
  EXPECT_TRUE(views);
  EXPECT_TRUE(coverage);
}

}  // namespace ps::testkit
