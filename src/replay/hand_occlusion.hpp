#pragma once
// The hand's half of an AR frame's occlusion, one path for the live loop (live/sculpt_loop.cpp),
// the AR recorder of `replay` and `demo` (app/ar_recorder.cpp) and `bench frame`: per frame, the
// board's look learned and the hand mask made (tracking::HandMasker) when the frame has its own
// board pose; the mask then goes over the rendered view through render::occludeByHand
// (render/occlusion_composite.hpp).
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <span>

#include "tracking/hand_mask.hpp"
#include "tracking/tracker.hpp"

namespace ps::replay {

class HandOcclusion {
 public:
  explicit HandOcclusion(tracking::HandMaskConfig config = {});
  // Whether a frame may learn and mask: the planet posed and the board's pose this frame's own
  // (measured, or held while the camera stands still). A pose held or carried over a moving
  // camera would compare the board with what is beside it.
  static bool masks(const tracking::MarkerEstimate& board,
                    const std::optional<tracking::Pose>& planetInCamera);
  // This frame's soft mask (CV_32F, 1: the camera image over the planet), empty when nothing is
  // in front of the planet (no pixel over 0.5) or the frame does not mask. `enabled` false (the
  // live panel's toggle, `--no-hand-mask`): nothing is learned, and the model starts afresh when
  // it is on again (what it held may have changed meanwhile). `image`: the undistorted frame the
  // planet is drawn over, `K` its pinhole; `radius`: the planet's bounding sphere in the board's
  // metres. `toolTriangles` (the tracked tool, planet frame, `scale` planet metres per board
  // metre: StepResult's): the board's look is not learned where the tool covers it
  // (toolFootprint), or it would be seen as a change where the tool was once the tool moves;
  // nor anywhere for kToolLostFrames after the tool was last tracked (lost under a hand or in a
  // blur, it is still over the board, where no footprint says).
  cv::Mat update(bool enabled, const cv::Mat& image, const cv::Matx33d& K,
                 const tracking::MarkerEstimate& board,
                 const std::optional<tracking::Pose>& planetInCamera, double radius,
                 std::span<const Eigen::Vector3d> toolTriangles = {}, double scale = 1);
  // The pixels (CV_8U 255, `size`) the tool's triangles cover seen from `planetInCamera`'s
  // camera, grown by a margin of its blur and its pose's error: a tenth of the tool's projected
  // size within the image (a tool near the camera moves and blurs over more pixels), 4 to 32 px.
  // Empty when no triangle wholly in front of the camera reaches into the image.
  static constexpr int kToolLostFrames = 30;
  static cv::Mat toolFootprint(cv::Size size, const cv::Matx33d& K,
                               const tracking::Pose& planetInCamera, double scale,
                               std::span<const Eigen::Vector3d> toolTriangles);
  // The last update's time (ms; 0 when it did not mask).
  double lastMs() const { return lastMs_; }

 private:
  tracking::HandMasker masker_;
  bool on_ = false;                        // `enabled` at the last update
  int framesSinceTool_ = kToolLostFrames;  // masked frames since the tool was last tracked
  double lastMs_ = 0;
};

}  // namespace ps::replay
