#pragma once
// What every calibration target shares (the ChArUco board, charuco_calibration.hpp; the plain
// chessboard, chessboard_calibration.hpp): the views kept (enough corners, not on one line, the
// board moved since the last kept view), how much of the image their corners covered on a
// coarse grid, the thresholds a calibration must meet, the judgement of a solver's result
// against them (a poor result lists its problems and is not to be written), and the file.
// A target finds its corners (with ids: a corner's place on the board) and solves; the rest is
// here, once.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"

namespace ps::tracking {

struct CalibrationThresholds {
  int minViews = 12;          // views kept
  int minCornersPerView = 8;  // chessboard corners for a view to count
  double minViewShiftPx = 0;  // mean corner motion since the last kept view (video: ~20 px)
  int maxViews = 60;          // later views are ignored (calibration time grows with them)
  double maxRmsPx = 1.0;      // RMS reprojection error
  double minCoverage = 0.6;   // fraction of the grid cells with a corner in some view
  int gridColumns = 8, gridRows = 6;
  double maxFocalStdRel = 0.01;   // standard deviation of fx, fy over fx, fy
  double maxCentreStdRel = 0.02;  // standard deviation of cx, cy over the image width
  void validate() const;          // core::InputError
};

struct CalibrationFlags {
  bool fixK3 = true;  // estimate k1, k2, p1, p2 and keep k3 = 0 (webcams; k3 overfits)
  bool fixAspect = false;
  bool zeroTangent = false;
  int opencvFlags() const;  // cv::CALIB_* for calibrateCamera and calibrateCameraCharuco
};

struct ViewResult {
  int markers = 0;  // ArUco markers of the board found (ChArUco boards)
  int corners = 0;  // chessboard corners found
  bool kept = false;
  std::string reason;  // why not kept ("", "too few corners", "did not move", "enough views")
};

struct Coverage {
  int columns = 0, rows = 0;
  std::vector<int> counts;  // corners per cell, row-major
  int covered() const;
  double fraction() const;
  // One text row per grid row: '#' covered, '.' empty.
  std::vector<std::string> map() const;
};

struct CalibrationResult {
  CameraCalibration calibration;
  double rms = 0;
  // Standard deviations as the solver reports them: fx, fy, cx, cy, k1, k2, p1, p2, k3 (a fixed
  // parameter reports 0).
  std::vector<double> stdDeviations;
  std::vector<double> perViewRms;
  int views = 0;
  int corners = 0;
  double coverage = 0;
  bool acceptable = false;
  std::vector<std::string> problems;  // why it is not acceptable (one line each)
};

// The views a calibrator has kept: their corners with ids, the image size, the coverage.
class CalibrationViews {
 public:
  explicit CalibrationViews(CalibrationThresholds thresholds);
  const CalibrationThresholds& thresholds() const { return thresholds_; }
  // The first image fixes the size; another size is core::InputError naming `name`.
  void checkImageSize(cv::Size size, const std::string& name);
  // Keeps the view when it qualifies (the rules above; `collinear`: the target found its
  // corners on one line). core::InputError for mismatched corners and ids, or no image size.
  ViewResult add(const std::vector<cv::Point2f>& corners, const std::vector<int>& ids,
                 const std::string& name, bool collinear);

  int views() const { return int(corners_.size()); }
  bool full() const { return views() >= thresholds_.maxViews; }
  cv::Size imageSize() const { return size_; }
  const Coverage& coverage() const { return coverage_; }
  const std::vector<std::vector<cv::Point2f>>& corners() const { return corners_; }
  const std::vector<std::vector<int>>& ids() const { return ids_; }

 private:
  CalibrationThresholds thresholds_;
  cv::Size size_{0, 0};
  Coverage coverage_;
  std::vector<std::vector<cv::Point2f>> corners_;
  std::vector<std::vector<int>> ids_;
  std::vector<std::string> names_;
};

// A number as the calibration's messages and file print it (`precision` significant digits).
std::string calibrationNumber(double v, int precision = 3);

// A solver's output (camera matrix, distortion, the intrinsics' standard deviations, per-view
// RMS) into `result`, judged against the views' thresholds: the problems that make it poor.
void judgeCalibration(const CalibrationViews& views, double rms, const cv::Mat& K,
                      const cv::Mat& dist, const cv::Mat& stdIntrinsics, const cv::Mat& perView,
                      CalibrationResult& result);

// Writes the calibration in OpenCV's YAML (what loadCalibration reads) plus how it was made:
// `target` (the board's description), views, coverage, RMS and the standard deviations. Atomic (a
// temporary file in the same folder, flushed and renamed). Throws std::runtime_error on I/O
// errors.
void saveCalibrationResult(const CalibrationResult& result, const std::string& target,
                           const std::filesystem::path& path);

}  // namespace ps::tracking
