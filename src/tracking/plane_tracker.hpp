#pragma once
// The board's pose while every one of its markers is hidden and the camera moves, from the
// plane the board lies on: the table and the sheet's margins that still show around the hands.
//
// The anchor is the last frame in which the board gave a pose. On the first frame that needs
// it, up to maxFeatures Shi-Tomasi corners are picked there (outside the tool's markers, grown)
// and put on the board's plane z = 0 by that pose (each corner's ray, undistorted, meets the
// plane). Each frame after, the corners are tracked by pyramidal Lucas-Kanade from the frame
// before and back (a corner under a hand or on the tool does not come back, and is dropped);
// every reanchorEvery frames those still tracked are tracked again from the anchor itself,
// seeded by where the chain put them, and snap back to it where the two agree (the chain's
// small slips do not add up). The camera's pose is solved from the corners' plane points and
// where they are now (RANSAC PnP, then Levenberg-Marquardt on the inliers): that is the board's
// pose, since the corners are in the board's frame. Outliers (a hand, the tool, a shadow) are
// dropped for good. Tracking fails, and the planet is lost, when fewer than minInliers corners
// agree, when they cover too little of the image, when the inliers' RMS reprojection error
// passes maxRmsPx, or when the pose jumps more than maxJump in a frame.
//
// With refillBelow > 0, when fewer corners than that are left (the camera has moved away from
// them) new ones are picked in the frame now and put on the plane by the pose just solved (at
// most as many as are left). Off by default: each refill bakes the pose's error of the moment
// into the new corners, and on board-hidden (a wood table, little of it in view) refilling
// under 60 corners drifted the planet to 10 mm off; without it that scene is carried for a few
// frames and then lost.
#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking {

struct PlaneTrackerConfig {
  // Corners picked in the anchor: at most maxFeatures, spread over a gridColumns x gridRows grid
  // (each cell takes its strongest first, its share of maxFeatures; what cells without texture
  // leave goes to the strongest of the rest).
  int maxFeatures = 150;
  int gridColumns = 8, gridRows = 6;
  double minDistancePx = 8;
  // Corners are picked and tracked on the frame made this many times smaller (INTER_AREA), by
  // pyramidal LK with a windowPx-wide window and pyramidMaxLevel levels above that frame
  // (OpenCV's maxLevel); the pose is solved at full resolution. Every distance below is in
  // full-resolution pixels.
  int downscale = 2;
  int windowPx = 9;
  int pyramidMaxLevel = 1;
  int minInliers = 20;
  double minSpread = 0.04;  // the inliers' bounding box covers this fraction of the image
  double ransacPx = 2.0;
  double maxRmsPx = 1.2;
  double maxJump = 0.05;  // m of the board's origin in one frame
  double backPx = 0.5;    // forward-backward check
  int reanchorEvery = 4;
  double reanchorAgreePx = 1.5;
  int refillBelow = 0;      // 0: never refill
  double maskMargin = 0.6;  // the tool's marker quads grown by this fraction of their size
  void validate() const;    // InputError naming the field
};

struct PlaneTrack {
  bool ok = false;
  Pose board;  // camera-from-board, when ok
  int features = 0, tracked = 0, inliers = 0;
  double rmsPx = 0;
  bool reanchored = false, refilled = false;
  std::string why;  // why tracking failed
};

class PlaneTracker {
 public:
  explicit PlaneTracker(PlaneTrackerConfig config = {});
  // A frame in which the board gave a pose: the anchor for the frames that follow. `exclude`:
  // the quads (pixels) of what is not on the table (the tool's markers). `imageIsOwned`: the
  // caller will not write into the image's buffer again, so it is kept without a copy.
  // `quality`: how well the pose is known (the number of markers that gave it). A reference of
  // lower quality than the one kept, taken from where the kept one's camera stood (the board's
  // pose within 10 mm and 2 degrees of it) does not replace it before tracking begins: the
  // plane's points are placed by the better pose (a hand coming over the board leaves fewer and
  // fewer markers to measure it by).
  void setReference(const cv::Mat& grey, const Pose& board,
                    const std::vector<std::array<cv::Point2d, 4>>& exclude,
                    bool imageIsOwned = false, int quality = 0);
  // The board's pose in this frame (grey, the reference's size), or why there is none. After a
  // failure it fails until the next reference.
  PlaneTrack track(const cv::Mat& grey, const CameraCalibration& calib,
                   const std::vector<std::array<cv::Point2d, 4>>& exclude = {});
  bool hasReference() const { return !pending_.empty() || !anchorPyramid_.empty(); }
  // Tracking has begun since the reference (and not failed).
  bool active() const { return started_ && !failed_; }
  void reset();

 private:
  bool start(const CameraCalibration& calib);
  // `work`: the frame at the working scale (downscale).
  void pick(const cv::Mat& work, const std::vector<cv::Mat>& pyramid, const Pose& board,
            const CameraCalibration& calib, const std::vector<std::array<cv::Point2d, 4>>& exclude,
            bool asAnchor);
  void reanchor(const std::vector<cv::Mat>& nowPyramid, PlaneTrack& r);
  cv::Mat working(const cv::Mat& grey) const;
  std::vector<cv::Mat> pyramid(const cv::Mat& work) const;
  // Working-scale pixels to full-resolution ones.
  std::vector<cv::Point2f> full(const std::vector<cv::Point2f>& work) const;
  PlaneTrackerConfig config_;
  cv::Mat pending_;  // the anchor frame, until a frame without the board needs it
  Pose pendingBoard_;
  int pendingQuality_ = 0;
  std::vector<std::array<cv::Point2d, 4>> pendingExclude_;
  std::vector<cv::Mat> anchorPyramid_, prevPyramid_;
  // Per corner: its place on the board plane, in the anchor (x < 0: picked later, no anchor),
  // and in the last frame.
  std::vector<cv::Point3f> plane_;
  std::vector<cv::Point2f> anchor_, prev_;  // working-scale pixels
  cv::Size fullSize_;
  double scaleX_ = 1, scaleY_ = 1;  // full-resolution pixels per working pixel
  Pose last_;
  bool started_ = false, failed_ = false;
  int frames_ = 0;
};

}  // namespace ps::tracking
