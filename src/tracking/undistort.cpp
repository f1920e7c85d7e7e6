#include "tracking/undistort.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace ps::tracking {

FrameUndistorter::FrameUndistorter(const CameraCalibration& c) : size_(c.imageSize) {
  if (c.distortion.empty() || cv::countNonZero(c.distortion) == 0) return;
  if (size_.width <= 0 || size_.height <= 0)
    throw std::invalid_argument("undistort: " + c.source + " has no image size");
  cv::initUndistortRectifyMap(cv::Mat(c.K), c.distortion, cv::noArray(), cv::Mat(c.K), size_,
                              CV_32FC1, mapX_, mapY_);
}

cv::Mat FrameUndistorter::apply(const cv::Mat& frame) const {
  if (!active() || frame.empty()) return frame;
  if (frame.size() != size_)
    throw std::invalid_argument("undistort: a " + std::to_string(frame.cols) + "x" +
                                std::to_string(frame.rows) + " frame for a " +
                                std::to_string(size_.width) + "x" + std::to_string(size_.height) +
                                " calibration");
  cv::Mat out;
  cv::remap(frame, out, mapX_, mapY_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return out;
}

}  // namespace ps::tracking
