#include "replay/hand_occlusion.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>

namespace ps::replay {

HandOcclusion::HandOcclusion(tracking::HandMaskConfig config) : masker_(std::move(config)) {}

bool HandOcclusion::masks(const tracking::MarkerEstimate& board,
                          const std::optional<tracking::Pose>& planetInCamera) {
  return planetInCamera && board.usable() && (board.measured || board.heldStill);
}

cv::Mat HandOcclusion::toolFootprint(cv::Size size, const cv::Matx33d& K,
                                     const tracking::Pose& planetInCamera, double scale,
                                     std::span<const Eigen::Vector3d> toolTriangles) {
  if (toolTriangles.size() < 3 || !(scale > 0)) return {};
  cv::Mat out = cv::Mat::zeros(size, CV_8U);
  cv::Rect2d extent;
  bool any = false;
  for (std::size_t i = 0; i + 2 < toolTriangles.size(); i += 3) {
    cv::Point corners[3];
    bool inFront = true;
    for (int k = 0; k < 3 && inFront; ++k) {
      const Eigen::Vector3d c = planetInCamera.apply(toolTriangles[i + k] / scale);
      inFront = c.z() > 1e-4;
      if (!inFront) break;
      const cv::Point2d p(K(0, 0) * c.x() / c.z() + K(0, 2), K(1, 1) * c.y() / c.z() + K(1, 2));
      if (!(std::abs(p.x) < 1e6 && std::abs(p.y) < 1e6)) inFront = false;
      corners[k] = cv::Point(int(std::lround(p.x)), int(std::lround(p.y)));
    }
    // A triangle reaching behind the camera is the stick's far end out of view: left out.
    if (!inFront) continue;
    cv::fillConvexPoly(out, corners, 3, cv::Scalar(255));
    const cv::Rect2d box = cv::boundingRect(std::vector<cv::Point>(corners, corners + 3));
    extent = any ? (extent | box) : box;
    any = true;
  }
  // The extent within the image (a stick reaching toward the camera projects far out), the
  // margin at most 32 px.
  extent &= cv::Rect2d(0, 0, size.width, size.height);
  if (!any || extent.area() <= 0) return {};
  const int margin =
      std::clamp(int(std::lround(0.1 * std::max(extent.width, extent.height))), 4, 32);
  // Grown only around the tool (a full frame's dilation by a 65 px disc costs milliseconds).
  const cv::Rect around =
      cv::Rect(int(std::floor(extent.x)) - 2 * margin, int(std::floor(extent.y)) - 2 * margin,
               int(std::ceil(extent.width)) + 4 * margin + 1,
               int(std::ceil(extent.height)) + 4 * margin + 1) &
      cv::Rect(0, 0, size.width, size.height);
  cv::Mat grown;
  cv::dilate(out(around), grown,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * margin + 1, 2 * margin + 1}));
  grown.copyTo(out(around));
  return out;
}

cv::Mat HandOcclusion::update(bool enabled, const cv::Mat& image, const cv::Matx33d& K,
                              const tracking::MarkerEstimate& board,
                              const std::optional<tracking::Pose>& planetInCamera, double radius,
                              std::span<const Eigen::Vector3d> toolTriangles, double scale) {
  lastMs_ = 0;
  if (!enabled) {
    on_ = false;
    return {};
  }
  if (!on_) {
    masker_.reset();
    framesSinceTool_ = kToolLostFrames;
  }
  on_ = true;
  if (!masks(board, planetInCamera)) return {};
  const auto t0 = std::chrono::steady_clock::now();
  cv::Mat tool = toolFootprint(image.size(), K, *planetInCamera, scale, toolTriangles);
  framesSinceTool_ = tool.empty() ? std::min(framesSinceTool_ + 1, kToolLostFrames) : 0;
  if (tool.empty() && framesSinceTool_ < kToolLostFrames)
    tool = cv::Mat(image.size(), CV_8U, cv::Scalar(255));
  cv::Mat mask = masker_.update(image, K, board.pose, planetInCamera->t, radius, tool).soft;
  if (cv::countNonZero(mask > 0.5f) == 0) mask.release();
  lastMs_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return mask;
}

}  // namespace ps::replay
