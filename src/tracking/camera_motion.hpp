#pragma once
// Has the camera moved since the planet board was last seen? While every board marker is hidden
// (a hand, the tool, the sheet's edge out of the image) the planet keeps its last pose only if
// the camera stands still; this judges that from the image itself.
//
// The reference is the last frame in which the board gave a pose. On the first frame without
// it, up to maxFeatures corners (Shi-Tomasi) are picked in the reference outside the markers
// (their quads grown by a margin: the tool moves, and the board's own markers are what is
// hidden now) and tracked into each new frame by pyramidal Lucas-Kanade, always from the
// reference, so a slow pan adds up instead of hiding under a per-frame threshold, and back again
// (a corner covered by a hand does not come back to where it was, and is left out). The camera
// is still when enough corners are found again and their median displacement is at most
// maxShiftPx: what still shows of the background has not moved.
#include <array>
#include <opencv2/core.hpp>
#include <vector>

namespace ps::tracking {

struct CameraMotionConfig {
  double maxShiftPx = 1.5;  // median displacement from the reference (full-resolution px)
  int maxFeatures = 150;
  // Corners found again (tracked there and back to within 0.5 px): fewer than minTracked, or
  // than this fraction of those picked, and the camera is not judged still.
  int minTracked = 10;
  double minTrackedFraction = 0.1;
  // The strongest firstBatch corners are tracked first: when at least half of them come back
  // and their median shift is at most a third of maxShiftPx the camera is still and the rest
  // are not tracked (most frames of a hold); otherwise every corner decides, as before.
  // 0: every corner, every frame.
  int firstBatch = 40;
  double maskMargin = 0.35;  // marker quads grown by this fraction of their size
  int downscale = 2;         // work on an image this many times smaller
  void validate() const;     // InputError naming the field
};

struct CameraMotion {
  bool judged = false;  // a reference existed and corners were found in it
  bool still = false;
  double medianShiftPx = 0;
  int features = 0, tracked = 0;
  bool early = false;  // decided on the first batch of corners
};

class CameraMotionJudge {
 public:
  explicit CameraMotionJudge(CameraMotionConfig config = {});
  // A frame in which the board gave a pose: the reference for the frames that follow. `exclude`
  // are the quads (pixels) of every marker in it. `imageIsOwned`: the caller will not write into
  // the image's buffer again (a grey frame made for this frame alone), so it is kept without a
  // copy.
  void setReference(const cv::Mat& image, const std::vector<std::array<cv::Point2d, 4>>& exclude,
                    bool imageIsOwned = false);
  // The frame now, against the reference (not judged without one).
  CameraMotion judge(const cv::Mat& image);
  bool hasReference() const { return !reference_.empty() || !pending_.empty(); }
  void reset();

 private:
  cv::Mat toWorkingGrey(const cv::Mat& image) const;
  void buildReference();  // pending_ and pendingQuads_ -> reference_ and mask_
  CameraMotionConfig config_;
  cv::Mat pending_;  // the last frame with the board, full size, until a judge needs it
  std::vector<std::array<cv::Point2d, 4>> pendingQuads_;
  cv::Mat reference_, mask_;
  std::vector<cv::Mat> referencePyramid_;
  std::vector<cv::Point2f> features_;
  bool featuresPicked_ = false;
};

}  // namespace ps::tracking
