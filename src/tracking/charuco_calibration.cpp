#include "tracking/charuco_calibration.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/input_error.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_family.hpp"

namespace ps::tracking {

namespace {

std::string num(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

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
    throw core::InputError("ChArUco square length " + num(squareLength) + " m is not > 0");
  if (!(markerLength > 0) || !(markerLength < squareLength))
    throw core::InputError("ChArUco marker length " + num(markerLength) +
                           " m must be > 0 and smaller than the square (" + num(squareLength) +
                           " m)");
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
         num(squareLength * 1e3) + " mm, markers " + num(markerLength * 1e3) + " mm, " + dictionary;
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

void CalibrationThresholds::validate() const {
  if (minViews < 3) throw core::InputError("at least 3 views are needed to calibrate (minViews)");
  if (maxViews < minViews)
    throw core::InputError("maxViews " + std::to_string(maxViews) + " is below minViews " +
                           std::to_string(minViews));
  if (minCornersPerView < 6)
    throw core::InputError("minCornersPerView must be >= 6 (calibrateCameraCharuco needs them)");
  if (!(maxRmsPx > 0)) throw core::InputError("the RMS threshold must be > 0 px");
  if (!(minCoverage >= 0 && minCoverage <= 1))
    throw core::InputError("the coverage threshold must be within 0..1");
  if (gridColumns < 1 || gridRows < 1 || gridColumns > 64 || gridRows > 64)
    throw core::InputError("the coverage grid needs 1 to 64 columns and rows");
  if (!(minViewShiftPx >= 0)) throw core::InputError("the view shift must be >= 0 px");
  if (!(maxFocalStdRel > 0) || !(maxCentreStdRel > 0))
    throw core::InputError("the standard deviation thresholds must be > 0");
}

int Coverage::covered() const {
  return int(std::count_if(counts.begin(), counts.end(), [](int c) { return c > 0; }));
}

double Coverage::fraction() const {
  return counts.empty() ? 0.0 : double(covered()) / double(counts.size());
}

std::vector<std::string> Coverage::map() const {
  std::vector<std::string> rowsText;
  for (int r = 0; r < rows; ++r) {
    std::string line;
    for (int c = 0; c < columns; ++c) line += counts[std::size_t(r * columns + c)] > 0 ? '#' : '.';
    rowsText.push_back(line);
  }
  return rowsText;
}

CharucoCalibrator::CharucoCalibrator(CharucoBoardSpec board, CalibrationThresholds thresholds,
                                     CalibrationFlags flags)
    : spec_(std::move(board)), thresholds_(thresholds), flags_(flags) {
  thresholds_.validate();
  board_ = spec_.create();
  params_ = cv::aruco::DetectorParameters::create();
  // interpolateCornersCharuco refines the chessboard corners itself (cornerSubPix); the marker
  // corners only place the local homographies.
  params_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
  coverage_.columns = thresholds_.gridColumns;
  coverage_.rows = thresholds_.gridRows;
  coverage_.counts.assign(std::size_t(coverage_.columns * coverage_.rows), 0);
}

ViewResult CharucoCalibrator::addImage(const cv::Mat& image, const std::string& name) {
  const cv::Mat grey = toGrey(image);
  if (size_.width == 0) {
    size_ = grey.size();
  } else if (grey.size() != size_) {
    throw core::InputError(name + ": image is " + std::to_string(grey.cols) + "x" +
                           std::to_string(grey.rows) + ", the first one was " +
                           std::to_string(size_.width) + "x" + std::to_string(size_.height));
  }
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  const int markers = findCharucoCorners(grey, board_, params_, corners, ids);
  ViewResult added = addCorners(corners, ids, name);
  added.markers = markers;
  return added;
}

ViewResult CharucoCalibrator::addCorners(const std::vector<cv::Point2f>& corners,
                                         const std::vector<int>& ids, const std::string& name) {
  ViewResult r;
  r.corners = int(ids.size());
  if (corners.size() != ids.size())
    throw core::InputError(name + ": " + std::to_string(corners.size()) + " corners but " +
                           std::to_string(ids.size()) + " ids");
  if (size_.width == 0) throw core::InputError("corners added before the image size is known");
  if (full()) {
    r.reason = "enough views";
    return r;
  }
  if (r.corners < thresholds_.minCornersPerView) {
    r.reason = "too few corners";
    return r;
  }
  if (cv::aruco::testCharucoCornersCollinear(board_, ids)) {
    r.reason = "corners on one line";
    return r;
  }
  if (thresholds_.minViewShiftPx > 0 && !corners_.empty()) {
    const auto& lastC = corners_.back();
    const auto& lastI = ids_.back();
    double sum = 0;
    int common = 0;
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const auto it = std::find(lastI.begin(), lastI.end(), ids[i]);
      if (it == lastI.end()) continue;
      sum += cv::norm(corners[i] - lastC[std::size_t(it - lastI.begin())]);
      ++common;
    }
    if (common >= 4 && sum / common < thresholds_.minViewShiftPx) {
      r.reason = "did not move";
      return r;
    }
  }
  corners_.push_back(corners);
  ids_.push_back(ids);
  names_.push_back(name);
  for (const auto& p : corners) {
    const int c = std::clamp(int(p.x / size_.width * coverage_.columns), 0, coverage_.columns - 1);
    const int w = std::clamp(int(p.y / size_.height * coverage_.rows), 0, coverage_.rows - 1);
    ++coverage_.counts[std::size_t(w * coverage_.columns + c)];
  }
  r.kept = true;
  return r;
}

CharucoCalibrationResult CharucoCalibrator::calibrate() const {
  if (corners_.empty())
    throw core::InputError("no view of the ChArUco board (" + spec_.describe() +
                           ") to calibrate from: is it the board that was printed?");
  CharucoCalibrationResult res;
  res.views = views();
  res.coverage = coverage_.fraction();
  for (const auto& c : corners_) res.corners += int(c.size());
  int flags = 0;
  if (flags_.fixK3) flags |= cv::CALIB_FIX_K3;
  if (flags_.fixAspect) flags |= cv::CALIB_FIX_ASPECT_RATIO;
  if (flags_.zeroTangent) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  cv::Mat K = cv::Mat::eye(3, 3, CV_64F), dist = cv::Mat::zeros(1, 5, CV_64F);
  cv::Mat stdIntrinsics, stdExtrinsics, perView;
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    res.rms =
        cv::aruco::calibrateCameraCharuco(corners_, ids_, board_, size_, K, dist, rvecs, tvecs,
                                          stdIntrinsics, stdExtrinsics, perView, flags);
  } catch (const cv::Exception& e) {
    res.acceptable = false;
    res.rms = std::numeric_limits<double>::infinity();
    res.problems.push_back("calibrateCameraCharuco failed: " + e.err);
    return res;
  }
  K.convertTo(K, CV_64F);
  dist.convertTo(dist, CV_64F);
  res.calibration.K = cv::Matx33d(K);
  res.calibration.distortion = dist.reshape(1, 1).colRange(0, 5).clone();
  res.calibration.imageSize = size_;
  res.calibration.rms = res.rms;
  res.calibration.source = "calibrate";
  stdIntrinsics.convertTo(stdIntrinsics, CV_64F);
  for (int i = 0; i < std::min(9, int(stdIntrinsics.total())); ++i)
    res.stdDeviations.push_back(stdIntrinsics.at<double>(i));
  perView.convertTo(perView, CV_64F);
  for (int i = 0; i < int(perView.total()); ++i) res.perViewRms.push_back(perView.at<double>(i));

  const auto& t = thresholds_;
  auto& p = res.problems;
  if (res.views < t.minViews)
    p.push_back(std::to_string(res.views) + " views of the board, at least " +
                std::to_string(t.minViews) + " needed (show it from more angles and distances)");
  if (!std::isfinite(res.rms) || res.rms > t.maxRmsPx)
    p.push_back("RMS reprojection error " + num(res.rms) + " px is above " + num(t.maxRmsPx) +
                " px (blur, a board that is not flat, or a wrong square size)");
  if (res.coverage < t.minCoverage)
    p.push_back("the corners covered " + num(100 * res.coverage, 2) + " % of the image's " +
                std::to_string(t.gridColumns) + "x" + std::to_string(t.gridRows) +
                " cells, at least " + num(100 * t.minCoverage, 2) +
                " % needed (bring the board to the image's edges and corners)");
  try {
    res.calibration.validate();
  } catch (const core::InputError& e) {
    p.push_back(std::string("the solver's camera is not valid: ") + e.what());
  }
  if (res.stdDeviations.size() >= 4) {
    const double fx = res.calibration.K(0, 0), fy = res.calibration.K(1, 1);
    const double sfx = res.stdDeviations[0], sfy = res.stdDeviations[1];
    const double scx = res.stdDeviations[2], scy = res.stdDeviations[3];
    if (!(sfx <= t.maxFocalStdRel * fx) || !(sfy <= t.maxFocalStdRel * fy))
      p.push_back("focal lengths uncertain: std fx " + num(sfx) + " px, fy " + num(sfy) +
                  " px, above " + num(100 * t.maxFocalStdRel) +
                  " % of the focal length (more views at a slant)");
    const double limit = t.maxCentreStdRel * size_.width;
    if (!(scx <= limit) || !(scy <= limit))
      p.push_back("principal point uncertain: std cx " + num(scx) + " px, cy " + num(scy) +
                  " px, above " + num(limit) + " px (more views, tilted both ways)");
  } else {
    p.push_back("no standard deviations from the solver");
  }
  res.acceptable = p.empty();
  return res;
}

void saveCharucoCalibration(const CharucoCalibrationResult& result, const CharucoBoardSpec& board,
                            const std::filesystem::path& path) {
  result.calibration.validate();
  const std::string tmp = path.string() + ".part";
  try {
    cv::FileStorage fs(tmp, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) throw std::runtime_error("cannot write " + tmp);
    const std::time_t now = std::time(nullptr);
    char when[64];
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
    fs << "info"
       << "planetsculpt calibrate: ChArUco board " + board.describe() + ", " +
              std::to_string(result.views) + " views, " + std::to_string(result.corners) +
              " corners";
    fs << "calibration_time" << when;
    const auto& c = result.calibration;
    fs << "image_width" << c.imageSize.width;
    fs << "image_height" << c.imageSize.height;
    fs << "camera_matrix" << cv::Mat(c.K);
    fs << "distortion_coefficients" << c.distortion.reshape(1, 1);
    fs << "avg_reprojection_error" << result.rms;
    // fx, fy, cx, cy, k1, k2, p1, p2, k3 (0 for a parameter that was fixed)
    fs << "std_deviations_intrinsics" << cv::Mat(result.stdDeviations, true).reshape(1, 1);
    fs << "views" << result.views;
    fs << "coverage" << result.coverage;
    fs << "per_view_reprojection_errors" << cv::Mat(result.perViewRms, true).reshape(1, 1);
    fs.release();
    // Flushed to disk before the rename: a crash leaves the old file or the whole new one.
    const int fd = ::open(tmp.c_str(), O_RDONLY);
    if (fd < 0 || ::fsync(fd) != 0) {
      if (fd >= 0) ::close(fd);
      throw std::runtime_error("cannot flush " + tmp);
    }
    ::close(fd);
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec)
      throw std::runtime_error("cannot rename " + tmp + " to " + path.string() + ": " +
                               ec.message());
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}

}  // namespace ps::tracking
