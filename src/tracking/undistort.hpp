#pragma once
// Camera frames as the calibration's pinhole camera would have taken them. The AR view draws the
// planet with the pinhole intrinsics K, so the image under it must show the scene through the
// same K: with lens distortion (a webcam's k1 of -0.3 moves the image's corners by tens of
// pixels) the planet would float off its board everywhere but at the centre. Frames are
// resampled with maps made once for the calibration and size (cv::initUndistortRectifyMap with
// the new camera K itself: the same pixel scale, the image's edges cropped where the lens bent
// them outward).
#include <opencv2/core.hpp>

#include "tracking/calibration.hpp"

namespace ps::tracking {

class FrameUndistorter {
 public:
  FrameUndistorter() = default;
  // `calibration` for the frames' size (CameraCalibration::forImageSize).
  explicit FrameUndistorter(const CameraCalibration& calibration);
  // False without distortion: frames are passed through untouched, at no cost.
  bool active() const { return !mapX_.empty(); }
  // The frame undistorted (the frame itself when not active). Throws std::invalid_argument for
  // a frame of another size than the calibration's.
  cv::Mat apply(const cv::Mat& frame) const;

 private:
  cv::Mat mapX_, mapY_;
  cv::Size size_;
};

}  // namespace ps::tracking
