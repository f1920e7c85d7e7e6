#include "tracking/charuco_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/input_error.hpp"
#include "tracking/calibration_views.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_family.hpp"

namespace ps::tracking {

namespace {

int arucoDictionaryOf(const std::string& name) {
  const FamilyInfo info = familyInfo(name);  // InputError for an unknown name
  if (info.apriltag || info.arucoDictionary < 0)
    throw core::InputError("ChArUco board dictionary '" + name +
                           "' is not an OpenCV dictionary (DICT_4X4_50, DICT_5X5_100, ...)");
  return info.arucoDictionary;
}

// Fills the pixels from round(x0) to round(x1) (exclusive) in both directions.
void fillBox(cv::Mat& image, double x0, double y0, double x1, double y1, uchar value) {
  const int ix0 = int(std::lround(x0)), ix1 = int(std::lround(x1));
  const int iy0 = int(std::lround(y0)), iy1 = int(std::lround(y1));
  const cv::Rect r = cv::Rect(ix0, iy0, ix1 - ix0, iy1 - iy0) & cv::Rect({}, image.size());
  if (r.area() > 0) image(r).setTo(value);
}

}  // namespace

void CharucoBoardSpec::validate() const {
  if (squaresX < 3 || squaresY < 3 || squaresX > 40 || squaresY > 40)
    throw core::InputError("ChArUco board of " + std::to_string(squaresX) + "x" +
                           std::to_string(squaresY) + " squares: each side needs 3 to 40");
  if (squaresY % 2 == 0)
    throw core::InputError("ChArUco board with " + std::to_string(squaresY) +
                           " rows: use an odd number of rows (OpenCV versions disagree on the "
                           "layout of even-row boards)");
  if (!(squareLength > 0) || !std::isfinite(squareLength))
    throw core::InputError("ChArUco square length " + calibrationNumber(squareLength) +
                           " m is not > 0");
  if (!(markerLength > 0) || !(markerLength < squareLength))
    throw core::InputError("ChArUco marker length " + calibrationNumber(markerLength) +
                           " m must be > 0 and smaller than the square (" +
                           calibrationNumber(squareLength) + " m)");
  const int dict = arucoDictionaryOf(dictionary);
  const int needed = (squaresX * squaresY) / 2;
  const int have = cv::aruco::getPredefinedDictionary(dict)->bytesList.rows;
  if (have < needed)
    throw core::InputError("ChArUco board of " + std::to_string(squaresX) + "x" +
                           std::to_string(squaresY) + " squares needs " + std::to_string(needed) +
                           " markers; " + dictionary + " has " + std::to_string(have));
}

cv::Ptr<cv::aruco::CharucoBoard> CharucoBoardSpec::create() const {
  validate();
  return cv::aruco::CharucoBoard::create(
      squaresX, squaresY, float(squareLength), float(markerLength),
      cv::aruco::getPredefinedDictionary(arucoDictionaryOf(dictionary)));
}

std::string CharucoBoardSpec::describe() const {
  return std::to_string(squaresX) + "x" + std::to_string(squaresY) + " squares of " +
         calibrationNumber(squareLength * 1e3) + " mm, markers " +
         calibrationNumber(markerLength * 1e3) + " mm, " + dictionary;
}

cv::Mat renderCharucoBoard(const CharucoBoardSpec& spec, double pixelsPerMetre, int marginPx) {
  const auto board = spec.create();
  if (!(pixelsPerMetre > 0) || marginPx < 0)
    throw core::InputError("board rendering needs pixelsPerMetre > 0 and a margin >= 0");
  const double W = spec.squaresX * spec.squareLength, H = spec.squaresY * spec.squareLength;
  const double s = pixelsPerMetre, m = marginPx;
  cv::Mat image(int(std::lround(H * s)) + 2 * marginPx, int(std::lround(W * s)) + 2 * marginPx,
                CV_8U, cv::Scalar(255));
  // Black squares: image square (row r, column c) with r, c of the same parity (what
  // CharucoBoard::draw does; with an odd number of rows the board frame agrees).
  for (int r = 0; r < spec.squaresY; ++r)
    for (int c = 0; c < spec.squaresX; ++c)
      if (r % 2 == c % 2)
        fillBox(image, m + c * spec.squareLength * s, m + r * spec.squareLength * s,
                m + (c + 1) * spec.squareLength * s, m + (r + 1) * spec.squareLength * s, 0);
  // Markers: objPoints[i][0] is the marker's top-left corner (OpenCV 4.6: board x right, y down
  // the printed image, origin at the board's top-left corner).
  const int cells = board->dictionary->markerSize + 2;
  const double cell = spec.markerLength / cells;
  for (std::size_t i = 0; i < board->ids.size(); ++i) {
    cv::Mat bits;
    cv::aruco::drawMarker(board->dictionary, board->ids[i], cells, bits, 1);
    const double x0 = board->objPoints[i][0].x, y0 = board->objPoints[i][0].y;
    for (int a = 0; a < cells; ++a)
      for (int b = 0; b < cells; ++b)
        fillBox(image, m + (x0 + b * cell) * s, m + (y0 + a * cell) * s,
                m + (x0 + (b + 1) * cell) * s, m + (y0 + (a + 1) * cell) * s,
                bits.at<uchar>(a, b) ? 255 : 0);
  }
  return image;
}

int findCharucoCorners(const cv::Mat& image, const cv::Ptr<cv::aruco::CharucoBoard>& board,
                       const cv::Ptr<cv::aruco::DetectorParameters>& params,
                       std::vector<cv::Point2f>& corners, std::vector<int>& ids) {
  const cv::Mat grey = toGrey(image);
  corners.clear();
  ids.clear();
  std::vector<std::vector<cv::Point2f>> markerCorners, rejected;
  std::vector<int> markerIds;
  cv::aruco::detectMarkers(grey, board->dictionary, markerCorners, markerIds, params, rejected);
  if (markerIds.size() >= 2) {
    cv::aruco::interpolateCornersCharuco(markerCorners, markerIds, grey, board, corners, ids);
    // OpenCV 4.6 stops its own cornerSubPix at 0.1 px and starts it from marker corners that
    // sit about 0.5 px inside the markers: its chessboard corners came out 0.5-0.7 px off on
    // rendered boards. Refined again here, to convergence, each in a window that keeps clear of
    // the nearest marker corner (a window that reaches one snaps to it); a corner that moves
    // further than its window allows is dropped.
    std::vector<cv::Point2f> keptCorners;
    std::vector<int> keptIds;
    for (std::size_t i = 0; i < corners.size(); ++i) {
      double clear = 1e9;
      for (const auto& q : markerCorners)
        for (const auto& m : q)
          clear = std::min(
              clear, double(std::max(std::abs(m.x - corners[i].x), std::abs(m.y - corners[i].y))));
      const int half = std::min(10, int(0.6 * clear));
      if (half < 2) continue;  // too small or too close to a marker to refine
      std::vector<cv::Point2f> p{corners[i]};
      cv::cornerSubPix(
          grey, p, cv::Size(half, half), cv::Size(-1, -1),
          cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-3));
      if (cv::norm(p[0] - corners[i]) > 0.5 * half + 1.0) continue;
      if (p[0].x < 2 || p[0].y < 2 || p[0].x > grey.cols - 3 || p[0].y > grey.rows - 3) continue;
      keptCorners.push_back(p[0]);
      keptIds.push_back(ids[i]);
    }
    corners = std::move(keptCorners);
    ids = std::move(keptIds);
  }
  return int(markerIds.size());
}

CharucoCalibrator::CharucoCalibrator(CharucoBoardSpec board, CalibrationThresholds thresholds,
                                     CalibrationFlags flags)
    : spec_(std::move(board)), flags_(flags), views_(thresholds) {
  board_ = spec_.create();
  params_ = cv::aruco::DetectorParameters::create();
  // interpolateCornersCharuco refines the chessboard corners itself (cornerSubPix); the marker
  // corners only place the local homographies.
  params_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
}

ViewResult CharucoCalibrator::addImage(const cv::Mat& image, const std::string& name) {
  const cv::Mat grey = toGrey(image);
  views_.checkImageSize(grey.size(), name);
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  const int markers = findCharucoCorners(grey, board_, params_, corners, ids);
  ViewResult added = addCorners(corners, ids, name);
  added.markers = markers;
  return added;
}

ViewResult CharucoCalibrator::addCorners(const std::vector<cv::Point2f>& corners,
                                         const std::vector<int>& ids, const std::string& name) {
  const bool collinear = int(ids.size()) >= views_.thresholds().minCornersPerView &&
                         cv::aruco::testCharucoCornersCollinear(board_, ids);
  return views_.add(corners, ids, name, collinear);
}

CharucoCalibrationResult CharucoCalibrator::calibrate() const {
  if (views_.views() == 0)
    throw core::InputError("no view of the ChArUco board (" + spec_.describe() +
                           ") to calibrate from: is it the board that was printed?");
  CharucoCalibrationResult res;
  cv::Mat K = cv::Mat::eye(3, 3, CV_64F), dist = cv::Mat::zeros(1, 5, CV_64F);
  cv::Mat stdIntrinsics, stdExtrinsics, perView;
  std::vector<cv::Mat> rvecs, tvecs;
  double rms = 0;
  try {
    rms = cv::aruco::calibrateCameraCharuco(
        views_.corners(), views_.ids(), board_, views_.imageSize(), K, dist, rvecs, tvecs,
        stdIntrinsics, stdExtrinsics, perView, flags_.opencvFlags());
  } catch (const cv::Exception& e) {
    res.views = views_.views();
    res.coverage = views_.coverage().fraction();
    res.acceptable = false;
    res.rms = std::numeric_limits<double>::infinity();
    res.problems.push_back("calibrateCameraCharuco failed: " + e.err);
    return res;
  }
  judgeCalibration(views_, rms, K, dist, stdIntrinsics, perView, res);
  return res;
}

void saveCharucoCalibration(const CharucoCalibrationResult& result, const CharucoBoardSpec& board,
                            const std::filesystem::path& path) {
  saveCalibrationResult(result, "ChArUco board " + board.describe(), path);
}

}  // namespace ps::tracking
