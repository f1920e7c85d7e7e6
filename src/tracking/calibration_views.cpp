#include "tracking/calibration_views.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <sstream>

#include "core/input_error.hpp"

namespace ps::tracking {

std::string calibrationNumber(double v, int precision) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

void CalibrationThresholds::validate() const {
  if (minViews < 3) throw core::InputError("at least 3 views are needed to calibrate (minViews)");
  if (maxViews < minViews)
    throw core::InputError("maxViews " + std::to_string(maxViews) + " is below minViews " +
                           std::to_string(minViews));
  if (minCornersPerView < 6)
    throw core::InputError("minCornersPerView must be >= 6 (the solvers need them)");
  if (!(maxRmsPx > 0)) throw core::InputError("the RMS threshold must be > 0 px");
  if (!(minCoverage >= 0 && minCoverage <= 1))
    throw core::InputError("the coverage threshold must be within 0..1");
  if (gridColumns < 1 || gridRows < 1 || gridColumns > 64 || gridRows > 64)
    throw core::InputError("the coverage grid needs 1 to 64 columns and rows");
  if (!(minViewShiftPx >= 0)) throw core::InputError("the view shift must be >= 0 px");
  if (!(maxFocalStdRel > 0) || !(maxCentreStdRel > 0))
    throw core::InputError("the standard deviation thresholds must be > 0");
}

int CalibrationFlags::opencvFlags() const {
  int flags = 0;
  if (fixK3) flags |= cv::CALIB_FIX_K3;
  if (fixAspect) flags |= cv::CALIB_FIX_ASPECT_RATIO;
  if (zeroTangent) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  return flags;
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

CalibrationViews::CalibrationViews(CalibrationThresholds thresholds) : thresholds_(thresholds) {
  thresholds_.validate();
  coverage_.columns = thresholds_.gridColumns;
  coverage_.rows = thresholds_.gridRows;
  coverage_.counts.assign(std::size_t(coverage_.columns * coverage_.rows), 0);
}

void CalibrationViews::checkImageSize(cv::Size size, const std::string& name) {
  if (size_.width == 0) {
    size_ = size;
  } else if (size != size_) {
    throw core::InputError(name + ": image is " + std::to_string(size.width) + "x" +
                           std::to_string(size.height) + ", the first one was " +
                           std::to_string(size_.width) + "x" + std::to_string(size_.height));
  }
}

ViewResult CalibrationViews::add(const std::vector<cv::Point2f>& corners,
                                 const std::vector<int>& ids, const std::string& name,
                                 bool collinear) {
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
  if (collinear) {
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

void judgeCalibration(const CalibrationViews& views, double rms, const cv::Mat& Kin,
                      const cv::Mat& distIn, const cv::Mat& stdIn, const cv::Mat& perViewIn,
                      CalibrationResult& res) {
  res.rms = rms;
  res.views = views.views();
  res.coverage = views.coverage().fraction();
  res.corners = 0;
  for (const auto& c : views.corners()) res.corners += int(c.size());
  cv::Mat K, dist, stdIntrinsics, perView;
  Kin.convertTo(K, CV_64F);
  distIn.convertTo(dist, CV_64F);
  const cv::Size size = views.imageSize();
  res.calibration.K = cv::Matx33d(K);
  res.calibration.distortion = dist.reshape(1, 1).colRange(0, 5).clone();
  res.calibration.imageSize = size;
  res.calibration.rms = rms;
  res.calibration.source = "calibrate";
  res.stdDeviations.clear();
  res.perViewRms.clear();
  if (!stdIn.empty()) stdIn.convertTo(stdIntrinsics, CV_64F);
  for (int i = 0; i < std::min(9, int(stdIntrinsics.total())); ++i)
    res.stdDeviations.push_back(stdIntrinsics.at<double>(i));
  if (!perViewIn.empty()) perViewIn.convertTo(perView, CV_64F);
  for (int i = 0; i < int(perView.total()); ++i) res.perViewRms.push_back(perView.at<double>(i));

  const auto& t = views.thresholds();
  auto& p = res.problems;
  if (res.views < t.minViews)
    p.push_back(std::to_string(res.views) + " views of the board, at least " +
                std::to_string(t.minViews) + " needed (show it from more angles and distances)");
  if (!std::isfinite(res.rms) || res.rms > t.maxRmsPx)
    p.push_back("RMS reprojection error " + calibrationNumber(res.rms) + " px is above " +
                calibrationNumber(t.maxRmsPx) +
                " px (blur, a board that is not flat, or a wrong square size)");
  if (res.coverage < t.minCoverage)
    p.push_back("the corners covered " + calibrationNumber(100 * res.coverage, 2) +
                " % of the image's " + std::to_string(t.gridColumns) + "x" +
                std::to_string(t.gridRows) + " cells, at least " +
                calibrationNumber(100 * t.minCoverage, 2) +
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
      p.push_back("focal lengths uncertain: std fx " + calibrationNumber(sfx) + " px, fy " +
                  calibrationNumber(sfy) + " px, above " +
                  calibrationNumber(100 * t.maxFocalStdRel) +
                  " % of the focal length (more views at a slant)");
    const double limit = t.maxCentreStdRel * size.width;
    if (!(scx <= limit) || !(scy <= limit))
      p.push_back("principal point uncertain: std cx " + calibrationNumber(scx) + " px, cy " +
                  calibrationNumber(scy) + " px, above " + calibrationNumber(limit) +
                  " px (more views, tilted both ways)");
  } else {
    p.push_back("no standard deviations from the solver");
  }
  res.acceptable = p.empty();
}

void saveCalibrationResult(const CalibrationResult& result, const std::string& target,
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
       << "planetsculpt calibrate: " + target + ", " + std::to_string(result.views) + " views, " +
              std::to_string(result.corners) + " corners";
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
