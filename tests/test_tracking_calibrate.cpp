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
#include "core/input_error.hpp"
#include "tracking/calibration.hpp"
#include "tracking/charuco_calibration.hpp"

using namespace ps;
using tracking::CharucoBoardSpec;

namespace {

constexpr double kPixelsPerMetre = 6000;  // texture of the board: 0.17 mm per pixel
constexpr int kMargin = 120;              // white paper around the board (texture pixels)
const cv::TermCriteria kExact(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12);

// The true camera of the synthetic views: off-centre principal point, barrel distortion.
struct TrueCamera {
  cv::Size size{640, 480};
  cv::Matx33d K{610, 0, 323.5, 0, 604, 236.25, 0, 0, 1};
  cv::Mat dist = (cv::Mat_<double>(1, 5) << -0.12, 0.06, 0.0008, -0.0006, 0.0);
};

cv::Matx33d rotation(double ax, double ay, double az) {
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
  ViewRenderer(const CharucoBoardSpec& spec, const TrueCamera& cam) : spec_(spec), cam_(cam) {
    texture_ = tracking::renderCharucoBoard(spec, kPixelsPerMetre, kMargin);
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
    const cv::Vec3d centre(spec_.squaresX * spec_.squareLength / 2,
                           spec_.squaresY * spec_.squareLength / 2, 0);
    // Aim the centre with the undistorted ray of that pixel.
    std::vector<cv::Point2d> p{{px, py}}, n;
    cv::undistortPoints(p, n, cam_.K, cam_.dist, cv::noArray(), cv::noArray(), kExact);
    const cv::Vec3d t = z * cv::Vec3d(n[0].x, n[0].y, 1.0) - R * centre;
    return render(R, t, seed);
  }

 private:
  static constexpr int kSs = 3;
  CharucoBoardSpec spec_;
  TrueCamera cam_;
  cv::Mat texture_;
  std::vector<cv::Point2f> rays_;
};

double deg(double d) {
  return d * M_PI / 180;
}

// View i of the standard set: the board's centre on a 3x3 grid over the image and at its
// middle, tilted 20-40 degrees both ways, turned in its plane, at 0.40-0.55 m.
cv::Mat standardView(const ViewRenderer& r, int i) {
  const double xs[3] = {150, 320, 490}, ys[3] = {130, 240, 350};
  const double px = xs[i % 3], py = ys[(i / 3) % 3];
  const double sx = (i % 2 ? 1 : -1), sy = ((i / 2) % 2 ? 1 : -1);
  const double ax = sx * deg(25 + 5 * (i % 5)), ay = sy * deg(25 + 6 * (i % 4));
  const double az = deg(-30 + 13 * i % 60);
  const double z = 0.40 + 0.015 * (i % 11);
  return r.view(px, py, z, ax, ay, az, std::uint64_t(i + 1));
}

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
  for (const auto& p : res.problems) ADD_FAILURE() << p;
  EXPECT_TRUE(res.acceptable);
  EXPECT_LT(res.rms, 0.5);
  const auto& K = res.calibration.K;
  ASSERT_GE(res.stdDeviations.size(), 4u);
  const double truth[4] = {cam.K(0, 0), cam.K(1, 1), cam.K(0, 2), cam.K(1, 2)};
  const double found[4] = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
  // Tolerance: fx, fy within 0.5 % (3 px), cx, cy within 3 px; and each within three of the
  // standard deviations the solver reports (which must be small: under 4 px).
  for (int i = 0; i < 4; ++i) {
    const double sd = res.stdDeviations[std::size_t(i)];
    EXPECT_NEAR(found[i], truth[i], 3.0) << "parameter " << i << " (fx, fy, cx, cy)";
    EXPECT_LE(std::abs(found[i] - truth[i]), 3 * sd) << "parameter " << i;
    EXPECT_GT(sd, 0.0);
    EXPECT_LT(sd, 4.0);
  }
  EXPECT_NEAR(res.calibration.distortion.at<double>(0), -0.12, 0.02);
  EXPECT_EQ(res.calibration.imageSize, cam.size);
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
  for (int i = 0; i < 4; ++i)
    calibrator.addImage(renderer.view(320, 240, 0.5, deg(i % 2 ? 25 : -25), deg(i < 2 ? 20 : -20),
                                      0, std::uint64_t(i + 1)));
  ASSERT_EQ(calibrator.views(), 4);
  const auto res = calibrator.calibrate();
  EXPECT_FALSE(res.acceptable);
  bool views = false, coverage = false;
  for (const auto& p : res.problems) {
    views |= p.find("4 views") != std::string::npos;
    coverage |= p.find("covered") != std::string::npos;
  }
  EXPECT_TRUE(views);
  EXPECT_TRUE(coverage);
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
  EXPECT_NEAR(c.K(0, 0), cam.K(0, 0), 3.0);
  EXPECT_NEAR(c.K(1, 1), cam.K(1, 1), 3.0);
  EXPECT_NEAR(c.K(0, 2), cam.K(0, 2), 3.0);
  EXPECT_NEAR(c.K(1, 2), cam.K(1, 2), 3.0);
  EXPECT_NEAR(c.distortion.at<double>(0), -0.12, 0.02);
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
