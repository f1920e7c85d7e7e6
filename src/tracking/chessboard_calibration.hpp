#pragma once
// Camera calibration from views of a plain chessboard (OpenCV's own tutorial target: what most
// people have printed). The corners are found as OpenCV's tutorial finds them
// (findChessboardCorners + cornerSubPix; findChessboardCornersSB where that finds none), the
// camera solved by calibrateCamera; views,
// coverage, thresholds, judgement and the file are calibration_views.hpp's, as for the ChArUco
// board. A chessboard has no markers: a view counts only when the whole inner grid is found.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/calibration_views.hpp"

namespace ps::tracking {

// The printed board: squaresX x squaresY squares (as `--squares` counts them), so
// (squaresX - 1) x (squaresY - 1) inner corners. Lengths in metres.
struct ChessboardSpec {
  int squaresX = 8;  // columns
  int squaresY = 6;  // rows
  double squareLength = 0.030;

  void validate() const;  // core::InputError naming the field
  cv::Size innerCorners() const { return {squaresX - 1, squaresY - 1}; }
  int cornerCount() const { return (squaresX - 1) * (squaresY - 1); }
  // The inner corners in the board's frame (x along a row, y down the rows, z = 0), in the order
  // findChessboardCorners reports them: row by row.
  std::vector<cv::Point3f> objectPoints() const;
  std::string describe() const;  // "8x6 squares of 30 mm (7x5 inner corners)"
};

// The board's canonical image: white paper, squaresX x squaresY squares (the top-left black)
// at `pixelsPerMetre`, with `marginPx` of white around it. 8-bit, 0 or 255 only. Board point
// (x, y) (metres from the first inner corner's square's top-left, i.e. the board's top-left
// corner) is at pixel (margin + x * ppm - 0.5, margin + y * ppm - 0.5).
cv::Mat renderChessboard(const ChessboardSpec& spec, double pixelsPerMetre, int marginPx = 0);

// The board's inner corners in an image (8-bit grey or BGR), row by row (OpenCV pixel
// convention); false (and no corners) when the whole grid is not found.
bool findChessboard(const cv::Mat& image, const ChessboardSpec& spec,
                    std::vector<cv::Point2f>& corners);

class ChessboardCalibrator {
 public:
  ChessboardCalibrator(ChessboardSpec board, CalibrationThresholds thresholds,
                       CalibrationFlags flags = {});
  const ChessboardSpec& board() const { return spec_; }
  const CalibrationThresholds& thresholds() const { return views_.thresholds(); }

  // Looks for the board in `image` (every image must have the first one's size, else
  // core::InputError naming `name`) and keeps the view when it qualifies.
  ViewResult addImage(const cv::Mat& image, const std::string& name = "");
  // Adds a view's corners found elsewhere (tests): the whole grid, row by row.
  ViewResult addCorners(const std::vector<cv::Point2f>& corners, cv::Size imageSize,
                        const std::string& name = "");

  int views() const { return views_.views(); }
  bool full() const { return views_.full(); }
  cv::Size imageSize() const { return views_.imageSize(); }
  const Coverage& coverage() const { return views_.coverage(); }
  // Every kept view's corners (row by row), in the order kept.
  const std::vector<std::vector<cv::Point2f>>& corners() const { return views_.corners(); }

  // Calibrates from the kept views (calibrateCamera with the flags' model). Never throws for a
  // poor calibration: the result says why. core::InputError when there is no view.
  CalibrationResult calibrate() const;

 private:
  ChessboardSpec spec_;
  CalibrationFlags flags_;
  CalibrationViews views_;
};

}  // namespace ps::tracking
