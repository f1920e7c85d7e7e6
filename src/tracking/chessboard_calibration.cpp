#include "tracking/chessboard_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/input_error.hpp"
#include "tracking/calibration_views.hpp"
#include "tracking/detector.hpp"

namespace ps::tracking {

void ChessboardSpec::validate() const {
  // findChessboardCornersSB needs at least 3 inner corners each way.
  if (squaresX < 4 || squaresY < 4 || squaresX > 40 || squaresY > 40)
    throw core::InputError("chessboard of " + std::to_string(squaresX) + "x" +
                           std::to_string(squaresY) +
                           " squares: each side needs 4 to 40 squares (3 to 39 inner corners)");
  if (!(squareLength > 0) || !std::isfinite(squareLength))
    throw core::InputError("chessboard square length " + calibrationNumber(squareLength) +
                           " m is not > 0");
}

std::vector<cv::Point3f> ChessboardSpec::objectPoints() const {
  std::vector<cv::Point3f> p;
  p.reserve(std::size_t(cornerCount()));
  for (int r = 1; r < squaresY; ++r)
    for (int c = 1; c < squaresX; ++c)
      p.emplace_back(float(c * squareLength), float(r * squareLength), 0.0f);
  return p;
}

std::string ChessboardSpec::describe() const {
  return std::to_string(squaresX) + "x" + std::to_string(squaresY) + " squares of " +
         calibrationNumber(squareLength * 1e3) + " mm (" + std::to_string(squaresX - 1) + "x" +
         std::to_string(squaresY - 1) + " inner corners)";
}

cv::Mat renderChessboard(const ChessboardSpec& spec, double pixelsPerMetre, int marginPx) {
  spec.validate();
  if (!(pixelsPerMetre > 0) || marginPx < 0)
    throw core::InputError("board rendering needs pixelsPerMetre > 0 and a margin >= 0");
  const double s = spec.squareLength * pixelsPerMetre;
  cv::Mat image(int(std::lround(spec.squaresY * s)) + 2 * marginPx,
                int(std::lround(spec.squaresX * s)) + 2 * marginPx, CV_8U, cv::Scalar(255));
  // Every square's edges at their rounded exact positions (no accumulated drift).
  for (int r = 0; r < spec.squaresY; ++r)
    for (int c = 0; c < spec.squaresX; ++c) {
      if ((r + c) % 2 != 0) continue;
      const int x0 = marginPx + int(std::lround(c * s)),
                x1 = marginPx + int(std::lround((c + 1) * s));
      const int y0 = marginPx + int(std::lround(r * s)),
                y1 = marginPx + int(std::lround((r + 1) * s));
      image(cv::Rect(x0, y0, x1 - x0, y1 - y0)).setTo(0);
    }
  return image;
}

bool findChessboard(const cv::Mat& image, const ChessboardSpec& spec,
                    std::vector<cv::Point2f>& corners) {
  const cv::Mat grey = toGrey(image);
  corners.clear();
  // OpenCV's tutorial pipeline (samples/cpp/calibration.cpp): findChessboardCorners, then
  // cornerSubPix in an 11x11 half-window, made smaller where neighbouring corners are under
  // 20 px apart (half-window 0.55 x their distance): on rendered views with 14-25 px squares the
  // tutorial's window, reaching the next corners' edges, moved cy by 5 px (0.6 x: cy 231.0 for
  // 236.25), where 0.55 x gives 235.4; on OpenCV's photographs (neighbours >= 20 px) the window
  // is the tutorial's, and so is the result. Where no grid is found, the sector-based detector
  // (findChessboardCornersSB, sub-pixel by itself) tries.
  const bool found = cv::findChessboardCorners(
      grey, spec.innerCorners(), corners,
      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
  if (found && int(corners.size()) == spec.cornerCount()) {
    double nearest = std::numeric_limits<double>::infinity();
    const int w = spec.innerCorners().width;
    for (std::size_t i = 0; i < corners.size(); ++i) {
      if ((int(i) + 1) % w != 0)
        nearest = std::min(nearest, double(cv::norm(corners[i] - corners[i + 1])));
      if (i + std::size_t(w) < corners.size())
        nearest = std::min(nearest, double(cv::norm(corners[i] - corners[i + std::size_t(w)])));
    }
    const int half = std::clamp(int(0.55 * nearest), 2, 11);
    cv::cornerSubPix(grey, corners, {half, half}, {-1, -1},
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-4));
    return true;
  }
  corners.clear();
  if (!cv::findChessboardCornersSB(grey, spec.innerCorners(), corners,
                                   cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY) ||
      int(corners.size()) != spec.cornerCount()) {
    corners.clear();
    return false;
  }
  return true;
}

ChessboardCalibrator::ChessboardCalibrator(ChessboardSpec board, CalibrationThresholds thresholds,
                                           CalibrationFlags flags)
    : spec_(board), flags_(flags), views_(thresholds) {
  spec_.validate();
}

ViewResult ChessboardCalibrator::addImage(const cv::Mat& image, const std::string& name) {
  const cv::Mat grey = toGrey(image);
  views_.checkImageSize(grey.size(), name);
  std::vector<cv::Point2f> corners;
  findChessboard(grey, spec_, corners);
  return addCorners(corners, grey.size(), name);
}

ViewResult ChessboardCalibrator::addCorners(const std::vector<cv::Point2f>& corners,
                                            cv::Size imageSize, const std::string& name) {
  views_.checkImageSize(imageSize, name);
  if (!corners.empty() && int(corners.size()) != spec_.cornerCount())
    throw core::InputError(name + ": " + std::to_string(corners.size()) +
                           " chessboard corners, the board has " +
                           std::to_string(spec_.cornerCount()));
  // A corner's id is its place in the grid: the views' motion is judged corner by corner.
  std::vector<int> ids(corners.size());
  std::iota(ids.begin(), ids.end(), 0);
  return views_.add(corners, ids, name, false);
}

CalibrationResult ChessboardCalibrator::calibrate() const {
  if (views_.views() == 0)
    throw core::InputError("no view of the chessboard (" + spec_.describe() +
                           ") to calibrate from: is it the board that was printed?");
  CalibrationResult res;
  const std::vector<std::vector<cv::Point3f>> objects(std::size_t(views_.views()),
                                                      spec_.objectPoints());
  cv::Mat K = cv::Mat::eye(3, 3, CV_64F), dist = cv::Mat::zeros(1, 5, CV_64F);
  cv::Mat stdIntrinsics, stdExtrinsics, perView;
  std::vector<cv::Mat> rvecs, tvecs;
  double rms = 0;
  try {
    rms = cv::calibrateCamera(objects, views_.corners(), views_.imageSize(), K, dist, rvecs, tvecs,
                              stdIntrinsics, stdExtrinsics, perView, flags_.opencvFlags());
  } catch (const cv::Exception& e) {
    res.views = views_.views();
    res.coverage = views_.coverage().fraction();
    res.rms = std::numeric_limits<double>::infinity();
    res.problems.push_back("calibrateCamera failed: " + e.err);
    return res;
  }
  judgeCalibration(views_, rms, K, dist, stdIntrinsics, perView, res);
  return res;
}

}  // namespace ps::tracking
