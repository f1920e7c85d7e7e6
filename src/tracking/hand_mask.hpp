#pragma once
// Where something (a hand) is in front of the planet, from the camera image alone (issue 42,
// the hand half): the board's appearance model (board_appearance.hpp) scores each texel of the
// board plane around the planet, the score goes back into the image through the board's
// homography, and within the planet's silhouette (a sphere of known radius standing on the
// board, its outline from the pose) the parts that differ from the board are kept when they are
// large enough, preferring those that reach outside the silhouette (a hand comes in from
// outside): a component that does may be small, one wholly inside must be larger and hold a
// strong core. The kept parts are closed, their holes filled, and feathered into a soft mask:
// 1 where the camera image should be shown over the rendered planet.
#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "tracking/board_appearance.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking {

struct HandMaskConfig {
  BoardAppearanceConfig appearance;
  double silhouetteMargin = 0.08;         // the searched disc's radius over the planet's, minus 1
  double ringFraction = 0.3;              // band outside the silhouette, in planet radii
  double strongScore = 1.6;               // a component's core, in score units (1 = differs)
  double minAreaFraction = 0.004;         // of the silhouette: a component reaching outside it
  double minInteriorAreaFraction = 0.03;  // of the silhouette: one wholly inside
  int openPx = 1;                         // speckle removal (radius, px)
  int closePx = 3;                        // gap closing (radius, px)
  double featherPx = 2.0;                 // Gaussian sigma of the soft edge (px)
  // InputError "hand mask: FIELD ..." (or "board appearance: FIELD ...") naming the bad field.
  void validate() const;
};

struct HandMaskFrame {
  cv::Mat soft;             // CV_32F at the image's size, [0, 1]: show the camera image there
  cv::Mat silhouette;       // CV_8U, 255 inside the planet's silhouette (radius as given)
  double coverage = 0;      // mean of `soft` over the silhouette
  int components = 0;       // kept
  cv::Vec3d gain{1, 1, 1};  // this frame's gain over the model (b, g, r)
};

// Pixels whose ray meets the sphere of `radius` at `centreCamera` (camera frame, in front of
// it): CV_8U 255 inside. `K` a pinhole.
cv::Mat sphereSilhouette(cv::Size size, const cv::Matx33d& K, const Eigen::Vector3d& centreCamera,
                         double radius);

class HandMasker {
 public:
  explicit HandMasker(HandMaskConfig config = {});
  const HandMaskConfig& config() const { return config_; }
  // One frame: `image` undistorted BGR or grey; `board` board -> camera; the planet's centre in
  // the camera frame and its radius (the board's metres). Learns the frame where it shows the
  // board, except where `notBoard` (CV_8U at the image's size, or empty) says it does not (the
  // tracked tool: BoardAppearance::view).
  HandMaskFrame update(const cv::Mat& image, const cv::Matx33d& K, const Pose& board,
                       const Eigen::Vector3d& planetCentreCamera, double radius,
                       const cv::Mat& notBoard = {});
  // Frames without a board pose: nothing to compare with (the model is kept).
  void reset() { appearance_.reset(); }
  const BoardAppearance& appearance() const { return appearance_; }

 private:
  cv::Mat keepComponents(const cv::Mat& score, const cv::Mat& silhouette, const cv::Mat& search,
                         int& keptCount) const;
  HandMaskConfig config_;
  BoardAppearance appearance_;
};

}  // namespace ps::tracking
