#pragma once
// What the board and the table around the planet look like without anything in front of them,
// learned in the board plane's rectified frame (issue 42, the hand half): each camera frame is
// warped through the homography of the tracked board pose (the board is planar, z = 0 in its
// frame) onto a square of texels centred on the planet's foot, and every texel keeps a running
// mean colour, updated only where the frame agrees with it. Because the model is carried by the
// board's pose it survives camera motion; because it is of the camera image (the planet is not
// in it), it holds what lies behind the planet as the camera sees it.
//
// The comparison is made to shrug off what is not an object: a global gain (and white balance)
// change is measured each frame as the per-channel median ratio of the frame to the model and
// divided out; a cast shadow darkens without changing chromaticity or texture, so a texel is
// foreground only when (a) its chromaticity differs, (b) it is brighter than the model or darker
// than the deepest shadow allowed, or (c) the model's texture (normalised cross-correlation over
// a window) is not there; each test is tolerant of one texel of misregistration and scaled by
// the camera's noise.
//
// Only the texels that matter are worked on (the mask reads the score where the planet is): the
// caller names a region of the square (the texels seen behind the planet's silhouette), and a
// view, its scores and its learning cover that region grown by margin() texels, so that the
// region's scores and learning are those the whole square would give. The rest of the square is
// learned one tile a frame (learnTiles² tiles in turn), so that a texel that comes behind the
// planet as the camera moves has been learned already. The frame's gain is measured on a sparse
// sample of the whole square.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "tracking/pose.hpp"

namespace ps::tracking {

struct BoardAppearanceConfig {
  double halfSizeM = 0.3;   // the modelled square's half side on the board plane (m)
  double texelM = 0.002;    // texel side (m)
  double learnRate = 0.05;  // running-mean weight once a texel has warmed up
  int warmupFrames = 8;     // a texel's first frames are averaged equally
  double noiseSigma = 4.0;  // the camera's noise (grey levels) that must not count as a change
  double chromaThreshold = 0.06;  // chromaticity distance (L2 of b, g, r / their sum)
  double shadowRatio = 0.3;       // darker than this fraction of the model: not a shadow
  double brightRatio = 1.35;      // brighter than this multiple of the model: something there
  double textureMinStd = 8.0;     // model texture (grey levels, window std) for the texture test
  double textureMinNcc = 0.3;     // correlation below which the model's texture is gone
  int textureWindow = 7;          // texels, odd
  double learnBelow = 0.6;        // texels learned where the score is below this...
  int learnGuardTexels = 4;       // ...and no texel within this distance is above it...
  // ...and the brightness is the model's times the frame's gain within this fraction: a shadow
  // is tolerated but not learned (a model that took it in would see its leaving as a change).
  double learnBrightnessTolerance = 0.15;
  // A texel kept from learning this many frames in a row takes the frame: what the model learned
  // there has left (a hand over the board when it was first seen) or the light there changed
  // for good. A hand held still over the planet for that long is taken as the board.
  int forgetAfterFrames = 300;
  // Outside the region the caller works on, the square is learned in learnTiles x learnTiles
  // tiles, one a frame: a texel there is learned (and counted toward forgetAfterFrames) once
  // every learnTiles² frames.
  int learnTiles = 6;
  // InputError "board appearance: FIELD ..." naming the first bad field.
  void validate() const;
};

// One camera frame seen in the board plane's rectified frame, over a region of the square.
struct PlaneView {
  cv::Rect region;             // the texels held (of the side() x side() square)
  cv::Mat image;               // CV_32FC3 (b, g, r) over the region, the camera image on the texels
  cv::Mat valid;               // CV_8U, 255 where the texel is in the image, in front of it
  cv::Matx33d imageFromTexel;  // texel (column, row, 1) of the square -> camera pixel (homogeneous)
  // CV_8U over the region, 255 where the caller knows the image shows something else than the
  // board (the tracked tool): never learned there (empty: nowhere).
  cv::Mat notBoard;
};

struct ForegroundScore {
  cv::Mat score;   // CV_32F per texel of the view: > 1 differs from the board; 0 where not learned
  cv::Mat steady;  // CV_8U, 255 where the brightness is the model's times the gain
};

struct FrameGain {
  cv::Vec3d gain{1, 1, 1};  // per channel, this frame over the model (b, g, r)
  int samples = 0;          // texels the gain was measured on
};

class BoardAppearance {
 public:
  explicit BoardAppearance(BoardAppearanceConfig config = {});
  const BoardAppearanceConfig& config() const { return config_; }
  int side() const { return side_; }
  cv::Rect square() const { return {0, 0, side_, side_}; }

  // Places the square for this frame and returns its texel -> image homography. `K` the
  // pinhole of the undistorted image; `board`: board -> camera; `centreOnBoard`: the planet's
  // foot on the board (m, board frame): the square's centre. A centre more than a quarter of the
  // square from the model's forgets the model.
  cv::Matx33d place(const cv::Matx33d& K, const Pose& board, const Eigen::Vector2d& centreOnBoard);
  // The texels (a box within the square) that the pixels of a convex region of the image see on
  // the board plane, from the points of its outline; the whole square where one of them sees no
  // plane (the horizon is in the region).
  cv::Rect texelsSeenIn(const cv::Matx33d& imageFromTexel,
                        const std::vector<cv::Point>& outline) const;
  // How far around a region a view must reach for the region's scores (and for learning within
  // it shrunk by one texel) to be those of a view of the whole square.
  int margin() const;
  // The frame's gain and white balance over the model: the per-channel median ratio over a
  // sparse sample of the square's learned texels. `image`: BGR or grey 8-bit, undistorted.
  FrameGain gain(const cv::Mat& image, const cv::Matx33d& imageFromTexel) const;
  // The camera image on the texels of `region` (within the square). `notBoard` (CV_8U at the
  // image's size, or empty): pixels known not to show the board, which are not learned (what is
  // learned there would be seen as a change once it moves: a ghost of the tool in the mask).
  PlaneView view(const cv::Mat& image, const cv::Matx33d& imageFromTexel, cv::Rect region,
                 const cv::Mat& notBoard = {});
  ForegroundScore foreground(const PlaneView& view, const cv::Vec3d& gain) const;
  // Learns the frame within `where` (square texels, within the view's region), except within
  // `skip` and the view's notBoard, where `fg` says it shows the board, unshadowed (texels never
  // seen take the frame).
  void learn(const PlaneView& view, const ForegroundScore& fg, const cv::Rect& where,
             const cv::Rect& skip = {});
  // This frame's tile of the square for learning beyond the worked region (one per call, in
  // turn).
  cv::Rect nextTile();
  void reset();
  // Texels learned at least once.
  int learnedTexels() const;

 private:
  BoardAppearanceConfig config_;
  int side_ = 0;
  int tile_ = 0;  // the next tile to learn
  Eigen::Vector2d centre_ = Eigen::Vector2d::Zero();
  bool centred_ = false;
  cv::Mat mean_;    // CV_32FC3
  cv::Mat count_;   // CV_32F, frames learned
  cv::Mat kept_;    // CV_32F, frames in a row kept from learning
  cv::Mat inside_;  // CV_8U 255 at the last image's size: warped to tell texels in the image
};

}  // namespace ps::tracking
