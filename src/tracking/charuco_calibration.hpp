#pragma once
// Camera calibration from views of a ChArUco board (OpenCV 4.6 contrib aruco API:
// CharucoBoard::create, detectMarkers, interpolateCornersCharuco, calibrateCameraCharuco).
//
// A CharucoCalibrator takes images one at a time (a video, an image folder, a live camera),
// keeps a view when enough chessboard corners were found and the board moved since the last
// kept view, and tracks how much of the image the corners have covered on a coarse grid (the
// feedback a user needs: "move the board into the empty cells"). calibrate() runs
// calibrateCameraCharuco with the intrinsics' standard deviations and judges the result
// against CalibrationThresholds; a poor result lists its problems and is not to be written.
#include <filesystem>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"

namespace ps::tracking {

// The printed board. squaresY (rows) must be odd: OpenCV changed the layout of even-row boards
// between versions, an odd-row board reads the same everywhere. Lengths in metres.
struct CharucoBoardSpec {
  int squaresX = 5;  // columns
  int squaresY = 7;  // rows (odd)
  double squareLength = 0.030;
  double markerLength = 0.022;
  std::string dictionary = "DICT_5X5_100";  // an OpenCV dictionary (marker_family.hpp)

  void validate() const;  // core::InputError naming the field
  cv::Ptr<cv::aruco::CharucoBoard> create() const;
  int cornerCount() const { return (squaresX - 1) * (squaresY - 1); }
  std::string describe() const;  // "5x7 squares of 30 mm, markers 22 mm, DICT_5X5_100"
};

// The board's canonical image: white paper, the chessboard's black squares and the markers, at
// `pixelsPerMetre` with every square and marker cell edge at the rounded exact position (no
// accumulated drift), plus `marginPx` of white around it. 8-bit, 0 or 255 only. OpenCV 4.6's
// board frame is the image's: origin at the top-left corner, x right, y down (z into the board),
// so board point (x, y) is at pixel (margin + x * ppm - 0.5, margin + y * ppm - 0.5).
cv::Mat renderCharucoBoard(const CharucoBoardSpec& spec, double pixelsPerMetre, int marginPx = 0);

// The board's chessboard corners in an image (8-bit grey or BGR): ArUco markers, then
// interpolateCornersCharuco, then cornerSubPix again to convergence (4.6's own refinement leaves
// them 0.5-0.7 px off). Returns the number of board markers found; `corners`/`ids` get the
// chessboard corners (OpenCV pixel convention) and their ids.
int findCharucoCorners(const cv::Mat& image, const cv::Ptr<cv::aruco::CharucoBoard>& board,
                       const cv::Ptr<cv::aruco::DetectorParameters>& params,
                       std::vector<cv::Point2f>& corners, std::vector<int>& ids);

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
};

struct ViewResult {
  int markers = 0;  // ArUco markers of the board found
  int corners = 0;  // chessboard corners interpolated
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

struct CharucoCalibrationResult {
  CameraCalibration calibration;
  double rms = 0;
  // Standard deviations as calibrateCameraCharuco reports them: fx, fy, cx, cy, k1, k2, p1, p2,
  // k3 (a fixed parameter reports 0).
  std::vector<double> stdDeviations;
  std::vector<double> perViewRms;
  int views = 0;
  int corners = 0;
  double coverage = 0;
  bool acceptable = false;
  std::vector<std::string> problems;  // why it is not acceptable (one line each)
};

class CharucoCalibrator {
 public:
  CharucoCalibrator(CharucoBoardSpec board, CalibrationThresholds thresholds,
                    CalibrationFlags flags = {});
  const CharucoBoardSpec& board() const { return spec_; }
  const CalibrationThresholds& thresholds() const { return thresholds_; }

  // Looks for the board in `image` (8-bit grey or BGR; every image must have the first one's
  // size, else core::InputError naming `name`) and keeps the view when it qualifies.
  ViewResult addImage(const cv::Mat& image, const std::string& name = "");
  // Adds corners found elsewhere (tests); same rules as addImage.
  ViewResult addCorners(const std::vector<cv::Point2f>& corners, const std::vector<int>& ids,
                        const std::string& name = "");

  int views() const { return int(corners_.size()); }
  bool full() const { return views() >= thresholds_.maxViews; }
  cv::Size imageSize() const { return size_; }
  const Coverage& coverage() const { return coverage_; }

  // Calibrates from the kept views. Never throws for a poor calibration: the result says why it
  // is poor. Throws core::InputError when there is nothing to calibrate from (no views).
  CharucoCalibrationResult calibrate() const;

 private:
  CharucoBoardSpec spec_;
  CalibrationThresholds thresholds_;
  CalibrationFlags flags_;
  cv::Ptr<cv::aruco::CharucoBoard> board_;
  cv::Ptr<cv::aruco::DetectorParameters> params_;
  cv::Size size_{0, 0};
  Coverage coverage_;
  std::vector<std::vector<cv::Point2f>> corners_;
  std::vector<std::vector<int>> ids_;
  std::vector<std::string> names_;
};

// Writes the calibration in OpenCV's YAML (what loadCalibration reads) plus how it was made:
// board, views, coverage, RMS and the standard deviations. Atomic (a temporary file in the same
// folder, renamed). Throws std::runtime_error on I/O errors.
void saveCharucoCalibration(const CharucoCalibrationResult& result, const CharucoBoardSpec& board,
                            const std::filesystem::path& path);

}  // namespace ps::tracking
