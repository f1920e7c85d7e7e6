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
#include "tracking/calibration_views.hpp"

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

using CharucoCalibrationResult = CalibrationResult;

class CharucoCalibrator {
 public:
  CharucoCalibrator(CharucoBoardSpec board, CalibrationThresholds thresholds,
                    CalibrationFlags flags = {});
  const CharucoBoardSpec& board() const { return spec_; }
  const CalibrationThresholds& thresholds() const { return views_.thresholds(); }

  // Looks for the board in `image` (8-bit grey or BGR; every image must have the first one's
  // size, else core::InputError naming `name`) and keeps the view when it qualifies.
  ViewResult addImage(const cv::Mat& image, const std::string& name = "");
  // Adds corners found elsewhere (tests); same rules as addImage.
  ViewResult addCorners(const std::vector<cv::Point2f>& corners, const std::vector<int>& ids,
                        const std::string& name = "");

  int views() const { return views_.views(); }
  bool full() const { return views_.full(); }
  cv::Size imageSize() const { return views_.imageSize(); }
  const Coverage& coverage() const { return views_.coverage(); }

  // Calibrates from the kept views. Never throws for a poor calibration: the result says why it
  // is poor. Throws core::InputError when there is nothing to calibrate from (no views).
  CharucoCalibrationResult calibrate() const;

 private:
  CharucoBoardSpec spec_;
  CalibrationFlags flags_;
  cv::Ptr<cv::aruco::CharucoBoard> board_;
  cv::Ptr<cv::aruco::DetectorParameters> params_;
  CalibrationViews views_;
};

// saveCalibrationResult (calibration_views.hpp) naming the ChArUco board.
void saveCharucoCalibration(const CharucoCalibrationResult& result, const CharucoBoardSpec& board,
                            const std::filesystem::path& path);

}  // namespace ps::tracking
