// ChArUco calibration: the rendered board reads back with every corner where it should be; a
// synthetic camera (known K and distortion) seen through views of the board is recovered; too
// few views, poor coverage and bad settings are refused; the written YAML reads back.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/build_paths.hpp"
#include "board_views.hpp"
#include "core/input_error.hpp"
#include "tracking/calibration.hpp"
#include "tracking/charuco_calibration.hpp"

using namespace ps;
using tracking::CharucoBoardSpec;

namespace {

using testkit::deg;
using testkit::kExact;
using testkit::standardView;
using testkit::TrueCamera;
using testkit::ViewRenderer;

void addStandardViews(tracking::CharucoCalibrator& calibrator, const ViewRenderer& r, int count) {
  for (int i = 0; i < count; ++i) {
    const auto v = calibrator.addImage(standardView(r, i), "view " + std::to_string(i));
    EXPECT_TRUE(v.kept) << "view " << i << ": " << v.reason << " (" << v.corners << " corners)";
  }
}

}  // namespace

TEST(TrackingCalibrate, RenderedBoardReadsBackWithEveryCornerInPlace) {
  const CharucoBoardSpec spec;
  const double ppm = 2000;  // 60 px squares
  const int margin = 40;
  const cv::Mat sharp = tracking::renderCharucoBoard(spec, ppm, margin);
  // Seen through a lens (a binary step has no unique sub-pixel corner).
  cv::Mat board;
  cv::GaussianBlur(sharp, board, {0, 0}, 1.0);
  ASSERT_EQ(sharp.cols, 2 * margin + int(std::lround(spec.squaresX * spec.squareLength * ppm)));
  ASSERT_EQ(sharp.rows, 2 * margin + int(std::lround(spec.squaresY * spec.squareLength * ppm)));
  const auto cb = spec.create();
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  const int markers = tracking::findCharucoCorners(
      board, cb, cv::aruco::DetectorParameters::create(), corners, ids);
  EXPECT_EQ(markers, int(cb->ids.size()));
  ASSERT_EQ(int(ids.size()), spec.cornerCount());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const cv::Point3f& o = cb->chessboardCorners[std::size_t(ids[i])];
    const cv::Point2d expected(margin + o.x * ppm - 0.5, margin + o.y * ppm - 0.5);
    EXPECT_LT(cv::norm(cv::Point2d(corners[i]) - expected), 0.1)
        << "corner id " << ids[i] << " at " << corners[i] << ", expected " << expected;
  }
}

TEST(TrackingCalibrate, RecoversAKnownCameraFromSyntheticViews) {
  const CharucoBoardSpec spec;
  const TrueCamera cam;
  const ViewRenderer renderer(spec, cam);
  tracking::CalibrationThresholds th;
  tracking::CharucoCalibrator calibrator(spec, th);
  addStandardViews(calibrator, renderer, 24);
  ASSERT_EQ(calibrator.views(), 24);
  const auto res = calibrator.calibrate();
  // Tolerance: fx, fy within 0.5 % (3 px), cx, cy within 3 px; and each within three of the
  // standard deviations the solver reports (which must be small: under 4 px).
  ASSERT_NO_FATAL_FAILURE(testkit::expectTrueIntrinsics(res, cam, 0.5, 0.0));
  for (int i = 0; i < 4; ++i) EXPECT_LT(res.stdDeviations[std::size_t(i)], 4.0);
  const auto& K = res.calibration.K;
  EXPECT_EQ(int(res.perViewRms.size()), 24);
  EXPECT_GE(res.coverage, th.minCoverage);
  // The written file reads back as the same camera, and no temporary file is left.
  const auto dir = std::filesystem::temp_directory_path() / "ps_test_calibrate";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  tracking::saveCharucoCalibration(res, spec, dir / "cam.yml");
  const auto back = tracking::loadCalibration(dir / "cam.yml");
  EXPECT_NEAR(back.K(0, 0), K(0, 0), 1e-9);
  EXPECT_NEAR(back.K(1, 2), K(1, 2), 1e-9);
  EXPECT_EQ(back.imageSize, cam.size);
  EXPECT_NEAR(back.rms, res.rms, 1e-12);
  EXPECT_FALSE(std::filesystem::exists(dir / "cam.yml.part"));
  std::filesystem::remove_all(dir);
}

TEST(TrackingCalibrate, RefusesTooFewViewsAndPoorCoverage) {
  const CharucoBoardSpec spec;
  const TrueCamera cam;
  const ViewRenderer renderer(spec, cam);
  tracking::CharucoCalibrator calibrator(spec, {});
  EXPECT_THROW(calibrator.calibrate(), core::InputError);  // nothing at all
  // Four views, all at the image's middle.
  for (int i = 0; i < 4; ++i) calibrator.addImage(testkit::middleView(renderer, i));
  ASSERT_EQ(calibrator.views(), 4);
  const auto res = calibrator.calibrate();
  testkit::expectTooFewAndUncovered(res);
  EXPECT_LT(res.coverage, 0.6);
  // The coverage map shows the empty cells.
  const auto map = calibrator.coverage().map();
  ASSERT_EQ(int(map.size()), 6);
  EXPECT_EQ(map[0], "........");
}

TEST(TrackingCalibrate, ViewsThatDidNotMoveAndEmptyImagesAreNotKept) {
  const CharucoBoardSpec spec;
  const TrueCamera cam;
  const ViewRenderer renderer(spec, cam);
  tracking::CalibrationThresholds th;
  th.minViewShiftPx = 20;
  tracking::CharucoCalibrator calibrator(spec, th);
  const cv::Mat a = renderer.view(300, 240, 0.5, deg(20), deg(10), 0, 1);
  EXPECT_TRUE(calibrator.addImage(a).kept);
  const auto again = calibrator.addImage(renderer.view(302, 241, 0.5, deg(20), deg(10), 0, 2));
  EXPECT_FALSE(again.kept);
  EXPECT_EQ(again.reason, "did not move");
  const auto empty = calibrator.addImage(cv::Mat(cam.size, CV_8U, cv::Scalar(128)));
  EXPECT_FALSE(empty.kept);
  EXPECT_EQ(empty.corners, 0);
  EXPECT_THROW(calibrator.addImage(cv::Mat(240, 320, CV_8U, cv::Scalar(0)), "small.png"),
               core::InputError);
  EXPECT_EQ(calibrator.views(), 1);
}

TEST(TrackingCalibrate, BadBoardsAreRefused) {
  CharucoBoardSpec even;
  even.squaresY = 6;
  EXPECT_THROW(even.validate(), core::InputError);
  CharucoBoardSpec big;
  big.markerLength = 0.035;
  EXPECT_THROW(big.validate(), core::InputError);
  CharucoBoardSpec tag;
  tag.dictionary = "tag36h11";
  EXPECT_THROW(tag.validate(), core::InputError);
  CharucoBoardSpec small;
  small.squaresX = 11;
  small.squaresY = 11;
  small.dictionary = "DICT_4X4_50";
  EXPECT_THROW(small.validate(), core::InputError);  // 60 markers needed
  tracking::CalibrationThresholds th;
  th.minViews = 2;
  EXPECT_THROW(th.validate(), core::InputError);
}

// `planetsculpt calibrate` end to end: a folder of rendered views in, a calibration file out
// that holds the true camera.
TEST(TrackingCalibrate, CommandCalibratesAFolderOfRenderedViews) {
  const std::filesystem::path exe = app::commandPath();
  if (!std::filesystem::exists(exe)) GTEST_SKIP() << "no " << exe << " in this build";
  const TrueCamera cam;
  const ViewRenderer renderer(CharucoBoardSpec{}, cam);
  const auto dir = std::filesystem::temp_directory_path() / "ps_test_calibrate_command";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "views");
  for (int i = 0; i < 16; ++i) {
    const auto file = dir / "views" / ("view" + std::to_string(100 + i) + ".png");
    ASSERT_TRUE(cv::imwrite(file.string(), standardView(renderer, i))) << file;
  }
  const std::string command = "'" + exe.string() + "' calibrate '" + (dir / "views").string() +
                              "' --out '" + (dir / "cam.yml").string() + "' > '" +
                              (dir / "log.txt").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const auto c = tracking::loadCalibration(dir / "cam.yml");
  testkit::expectNearTheTrueCamera(c, cam);
  EXPECT_EQ(c.imageSize, cam.size);
  EXPECT_LT(c.rms, 0.5);
  std::filesystem::remove_all(dir);
}

// OpenCV's FileStorage parsers loop forever on some malformed text (the fuzzer's finds): such
// files are refused, naming the file, before OpenCV reads them; well-formed YAML, XML and JSON
// calibrations still load.
TEST(TrackingCalibrate, MalformedFilesAreRefusedBeforeOpenCvParsesThem) {
  for (const std::string& text :
       {std::string("%YAML:1.\n-----0\n----\nd"), std::string("%YAML:1.\n t:d\n%Y\n-"),
        std::string("{\"camera_matrix\": [1, 2"),
        std::string("<?xml version=\"1.0\"?>\n<opencv_storage><a>")}) {
    try {
      (void)tracking::parseCalibration(text, "bad.yml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.yml: malformed calibration file"),
                std::string::npos)
          << e.what();
    }
  }
  cv::Mat K = (cv::Mat_<double>(3, 3) << 600, 0, 319.5, 0, 600, 239.5, 0, 0, 1);
  cv::Mat d = cv::Mat::zeros(1, 5, CV_64F);
  for (const char* ext : {".yml", ".xml", ".json"}) {
    cv::FileStorage fs(std::string("x") + ext,
                       cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                           (ext[1] == 'x'   ? cv::FileStorage::FORMAT_XML
                            : ext[1] == 'j' ? cv::FileStorage::FORMAT_JSON
                                            : cv::FileStorage::FORMAT_YAML));
    fs << "camera_matrix" << K << "distortion_coefficients" << d;
    const std::string text = fs.releaseAndGetString();
    const auto c = tracking::parseCalibration(text, std::string("good") + ext);
    EXPECT_EQ(c.K(0, 0), 600.0) << ext;
    EXPECT_EQ(c.K(1, 2), 239.5) << ext;
  }
}
