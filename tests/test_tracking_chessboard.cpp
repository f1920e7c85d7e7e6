// Chessboard calibration (issue 42 part 3): the rendered board reads back with every inner
// corner in place; a known camera (off-centre principal point, barrel distortion) is recovered
// from rendered views; poor calibrations and bad boards are refused; on real photographs
// (OpenCV's left01..14.jpg, Debian's opencv-doc) the result agrees with OpenCV's own tutorial
// pipeline (findChessboardCorners + cornerSubPix + calibrateCamera) on the same views.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/build_paths.hpp"
#include "board_views.hpp"
#include "core/input_error.hpp"
#include "error_of.hpp"
#include "fresh_dir.hpp"
#include "tracking/calibration.hpp"
#include "tracking/chessboard_calibration.hpp"

using namespace ps;
using testkit::deg;
using testkit::errorOf;
using testkit::TrueCamera;
using testkit::ViewRenderer;
using tracking::ChessboardSpec;

namespace {

// 8x6 squares of 20 mm (7x5 inner corners): small enough that the whole grid stays in the
// standard views (a chessboard counts only whole).
ChessboardSpec smallBoard() {
  ChessboardSpec b;
  b.squaresX = 8;
  b.squaresY = 6;
  b.squareLength = 0.020;
  return b;
}

// OpenCV's sample photographs: $PS_OPENCV_SAMPLES, else where Debian's opencv-doc puts them.
std::filesystem::path opencvSamples() {
  if (const char* env = std::getenv("PS_OPENCV_SAMPLES"); env && *env) return env;
  return "/usr/share/doc/opencv-doc/examples/data";
}

}  // namespace

TEST(TrackingChessboard, RenderedBoardReadsBackWithEveryCornerInPlace) {
  const ChessboardSpec spec = smallBoard();
  const double ppm = 3000;  // 60 px squares
  const int margin = 50;
  const cv::Mat sharp = tracking::renderChessboard(spec, ppm, margin);
  ASSERT_EQ(sharp.cols, 2 * margin + int(std::lround(spec.squaresX * spec.squareLength * ppm)));
  cv::Mat board;
  cv::GaussianBlur(sharp, board, {0, 0}, 1.0);
  std::vector<cv::Point2f> corners;
  ASSERT_TRUE(tracking::findChessboard(board, spec, corners));
  ASSERT_EQ(int(corners.size()), spec.cornerCount());
  // Whatever corner the detector starts from, each found corner is one of the board's, once.
  const auto objects = spec.objectPoints();
  std::vector<int> hits(objects.size(), 0);
  for (const auto& c : corners) {
    double best = 1e9;
    std::size_t at = 0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const cv::Point2d expected(margin + objects[i].x * ppm - 0.5,
                                 margin + objects[i].y * ppm - 0.5);
      const double d = cv::norm(cv::Point2d(c) - expected);
      if (d < best) best = d, at = i;
    }
    EXPECT_LT(best, 0.1) << "corner at " << c;
    ++hits[at];
  }
  for (std::size_t i = 0; i < hits.size(); ++i) EXPECT_EQ(hits[i], 1) << "board corner " << i;
  // No board, or a board of other squares: not found.
  EXPECT_FALSE(tracking::findChessboard(cv::Mat(480, 640, CV_8U, cv::Scalar(128)), spec, corners));
  EXPECT_TRUE(corners.empty());
  ChessboardSpec other = spec;
  other.squaresX = 10;
  EXPECT_FALSE(tracking::findChessboard(board, other, corners));
}

// Tolerance: fx, fy, cx, cy within 3 px of the truth (0.5 % of the focal length) and within
// three of the standard deviations the solver reports; k1 within 0.02.
TEST(TrackingChessboard, RecoversAKnownCameraFromSyntheticViews) {
  const ChessboardSpec spec = smallBoard();
  const TrueCamera cam;
  const ViewRenderer renderer(spec, cam);
  tracking::CalibrationThresholds th;
  tracking::ChessboardCalibrator calibrator(spec, th);
  int kept = 0;
  for (int i = 0; i < 24; ++i)
    kept +=
        calibrator.addImage(testkit::standardView(renderer, i), "view " + std::to_string(i)).kept
            ? 1
            : 0;
  ASSERT_GE(kept, 18) << "views whose whole grid was found";
  const auto res = calibrator.calibrate();
  ASSERT_NO_FATAL_FAILURE(testkit::expectTrueIntrinsics(res, cam, 0.3, 0.2));
  const auto& K = res.calibration.K;
  std::cout << "[chessboard synthetic] " << kept << " views: fx " << K(0, 0) << " fy " << K(1, 1)
            << " cx " << K(0, 2) << " cy " << K(1, 2) << " (truth " << cam.K(0, 0) << ", "
            << cam.K(1, 1) << ", " << cam.K(0, 2) << ", " << cam.K(1, 2) << "), RMS " << res.rms
            << " px\n";
}

TEST(TrackingChessboard, RefusesTooFewViewsPoorCoverageAndBadBoards) {
  const ChessboardSpec spec = smallBoard();
  const TrueCamera cam;
  const ViewRenderer renderer(spec, cam);
  tracking::ChessboardCalibrator calibrator(spec, {});
  EXPECT_NE(errorOf([&] { (void)calibrator.calibrate(); }).find("no view of the chessboard"),
            std::string::npos);
  // No board in the image: nothing kept, no corners.
  const auto empty = calibrator.addImage(cv::Mat(cam.size, CV_8U, cv::Scalar(128)), "grey.png");
  EXPECT_FALSE(empty.kept);
  EXPECT_EQ(empty.corners, 0);
  // Four views, all at the image's middle.
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(calibrator.addImage(testkit::middleView(renderer, i)).kept);
  testkit::expectTooFewAndUncovered(calibrator.calibrate());
  // Another image size, or corners of another board, are refused naming the view.
  EXPECT_NE(errorOf([&] {
              calibrator.addImage(cv::Mat(240, 320, CV_8U), "small.png");
            }).find("small.png: image is 320x240"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              calibrator.addCorners(std::vector<cv::Point2f>(12), cam.size, "v");
            }).find("v: 12 chessboard corners, the board has 35"),
            std::string::npos);
  // Bad boards.
  for (auto [x, y, mm] : {std::tuple{3, 6, 30.0}, std::tuple{8, 41, 30.0}, std::tuple{8, 6, 0.0}}) {
    ChessboardSpec b;
    b.squaresX = x, b.squaresY = y, b.squareLength = mm * 1e-3;
    EXPECT_THROW(b.validate(), core::InputError) << x << "x" << y << " of " << mm << " mm";
  }
}

// On OpenCV's own photographs of its 9x6-corner chessboard (10x7 squares), the result agrees with
// OpenCV's tutorial pipeline run on the same images: fx, fy, cx, cy within 1 %, RMS within
// 0.05 px, for the default model (k3 fixed) and for OpenCV's default (k3 estimated).
TEST(TrackingChessboard, AgreesWithOpenCvOnRealPhotographs) {
  const auto dir = opencvSamples();
  std::vector<std::filesystem::path> files;
  for (int i = 1; i <= 14; ++i) {
    char name[32];  // room for any int: -O1 cannot prove i <= 14
    std::snprintf(name, sizeof name, "left%02d.jpg", i);
    if (std::filesystem::exists(dir / name)) files.push_back(dir / name);
  }
  if (files.size() < 12)
    GTEST_SKIP() << "OpenCV's sample photographs left01..14.jpg are not in " << dir
                 << " (apt-get install opencv-doc, or set PS_OPENCV_SAMPLES to a folder with "
                    "them; docs/TRACKING.md)";
  ChessboardSpec spec;
  spec.squaresX = 10;
  spec.squaresY = 7;
  spec.squareLength = 0.025;
  for (const bool fixK3 : {true, false}) {
    tracking::CalibrationFlags flags;
    flags.fixK3 = fixK3;
    tracking::ChessboardCalibrator ours(spec, {}, flags);
    // OpenCV's samples/cpp/calibration.cpp: corners, then cornerSubPix in an 11x11 window.
    std::vector<std::vector<cv::Point2f>> reference;
    cv::Size size;
    for (const auto& f : files) {
      const cv::Mat grey = cv::imread(f.string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(grey.empty()) << f;
      size = grey.size();
      const auto v = ours.addImage(grey, f.filename().string());
      std::vector<cv::Point2f> c;
      const bool found = cv::findChessboardCorners(
          grey, spec.innerCorners(), c,
          cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_FAST_CHECK | cv::CALIB_CB_NORMALIZE_IMAGE);
      EXPECT_EQ(v.kept, found) << f.filename() << ": " << v.reason;
      if (!found || !v.kept) continue;
      cv::cornerSubPix(grey, c, {11, 11}, {-1, -1},
                       cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-4));
      reference.push_back(c);
    }
    ASSERT_GE(ours.views(), 12);
    ASSERT_EQ(int(reference.size()), ours.views());
    const auto res = ours.calibrate();
    for (const auto& p : res.problems) ADD_FAILURE() << p;
    cv::Mat K, dist;
    std::vector<cv::Mat> rvecs, tvecs;
    const double rms = cv::calibrateCamera(
        std::vector<std::vector<cv::Point3f>>(reference.size(), spec.objectPoints()), reference,
        size, K, dist, rvecs, tvecs, flags.opencvFlags());
    const cv::Matx33d& k = res.calibration.K;
    const double mine[4] = {k(0, 0), k(1, 1), k(0, 2), k(1, 2)};
    const double theirs[4] = {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2),
                              K.at<double>(1, 2)};
    const char* names[4] = {"fx", "fy", "cx", "cy"};
    std::cout << "[chessboard left*.jpg, k3 " << (fixK3 ? "fixed" : "estimated") << ", "
              << ours.views() << " views]";
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(mine[i], theirs[i], 0.01 * theirs[i]) << names[i];
      std::cout << " " << names[i] << " " << mine[i] << " vs " << theirs[i] << " ("
                << 100 * (mine[i] - theirs[i]) / theirs[i] << " %)";
    }
    EXPECT_NEAR(res.rms, rms, 0.05);
    std::cout << "; RMS " << res.rms << " vs " << rms << " px\n";
  }
}

// `planetsculpt calibrate FOLDER --pattern chessboard`: a folder of rendered views in, the true
// camera out; a missing or bad --squares, and ChArUco options, are refused.
TEST(TrackingChessboard, CommandCalibratesAFolderOfRenderedViews) {
  const std::filesystem::path exe = app::commandPath();
  if (!std::filesystem::exists(exe)) GTEST_SKIP() << "no " << exe << " in this build";
  const TrueCamera cam;
  const ViewRenderer renderer(smallBoard(), cam);
  const auto dir = testkit::freshDir("chessboard_command");
  std::filesystem::create_directories(dir / "views");
  for (int i = 0; i < 16; ++i) {
    const auto file = dir / "views" / ("view" + std::to_string(100 + i) + ".png");
    ASSERT_TRUE(cv::imwrite(file.string(), testkit::standardView(renderer, i))) << file;
  }
  // A board size that no view shows: each view is searched for it in vain (a few seconds each,
  // most of this test's time), so 4 of the 16 views make that refusal, the same search each.
  std::filesystem::create_directories(dir / "four_views");
  for (int i = 0; i < 4; ++i) {
    const std::string name = "view" + std::to_string(100 + i) + ".png";
    std::filesystem::copy_file(dir / "views" / name, dir / "four_views" / name);
  }
  auto run = [&](const std::string& options, const char* views = "views") {
    const std::string command = "'" + exe.string() + "' calibrate '" + (dir / views).string() +
                                "' --out '" + (dir / "cam.yml").string() + "' " + options + " > '" +
                                (dir / "log.txt").string() + "' 2>&1";
    const int rc = std::system(command.c_str());
    std::ifstream in(dir / "log.txt");
    const std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return std::pair{rc, log};
  };
  {
    const auto [rc, log] = run("--pattern chessboard --squares 8x6 --square-mm 20 --min-views 10");
    ASSERT_EQ(rc, 0) << log;
    const auto c = tracking::loadCalibration(dir / "cam.yml");
    testkit::expectNearTheTrueCamera(c, cam);
  }
  for (const auto& [options, message] :
       {std::pair{"--pattern chessboard", "needs --squares COLUMNSxROWS"},
        std::pair{"--pattern chessboard --squares 8", "--squares '8' is not COLUMNSxROWS"},
        std::pair{"--pattern chessboard --squares 3x6", "each side needs 4 to 40 squares"},
        std::pair{"--pattern chessboard --squares 8x6 --dictionary DICT_4X4_50",
                  "a chessboard has no markers"},
        std::pair{"--pattern circles", "--pattern 'circles' is not charuco or chessboard"},
        std::pair{"--pattern chessboard --squares 12x9", "inner corners) was never seen"}}) {
    const bool neverSeen = std::string(options).ends_with("12x9");
    const auto [rc, log] = run(options, neverSeen ? "four_views" : "views");
    EXPECT_NE(rc, 0) << options;
    EXPECT_NE(log.find(message), std::string::npos) << options << "\n" << log;
    if (neverSeen) {
      EXPECT_NE(log.find("0 view(s) kept of 4 frame(s)"), std::string::npos) << log;
    }
  }
}
