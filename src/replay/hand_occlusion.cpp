#include "replay/hand_occlusion.hpp"

#include <chrono>
#include <utility>

namespace ps::replay {

HandOcclusion::HandOcclusion(tracking::HandMaskConfig config) : masker_(std::move(config)) {}

bool HandOcclusion::masks(const tracking::MarkerEstimate& board,
                          const std::optional<tracking::Pose>& planetInCamera) {
  return planetInCamera && board.usable() && (board.measured || board.heldStill);
}

cv::Mat HandOcclusion::update(bool enabled, const cv::Mat& image, const cv::Matx33d& K,
                              const tracking::MarkerEstimate& board,
                              const std::optional<tracking::Pose>& planetInCamera, double radius) {
  lastMs_ = 0;
  if (!enabled) {
    on_ = false;
    return {};
  }
  if (!on_) masker_.reset();
  on_ = true;
  if (!masks(board, planetInCamera)) return {};
  const auto t0 = std::chrono::steady_clock::now();
  cv::Mat mask = masker_.update(image, K, board.pose, planetInCamera->t, radius).soft;
  if (cv::countNonZero(mask > 0.5f) == 0) mask.release();
  lastMs_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return mask;
}

}  // namespace ps::replay
