#include "tracking/camera_motion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <string>

#include "core/input_error.hpp"
#include "tracking/detector.hpp"

namespace ps::tracking {

void CameraMotionConfig::validate() const {
  auto bad = [](const std::string& what) { throw core::InputError("camera motion: " + what); };
  if (!(maxShiftPx > 0) || !std::isfinite(maxShiftPx)) bad("max shift (px) is not > 0");
  if (maxFeatures < 1) bad("max features is not >= 1");
  if (minTracked < 1) bad("min tracked is not >= 1");
  if (!(minTrackedFraction >= 0 && minTrackedFraction <= 1))
    bad("min tracked fraction not in [0, 1]");
  if (!(maskMargin >= 0) || !std::isfinite(maskMargin)) bad("mask margin is not >= 0");
  if (downscale < 1 || downscale > 8) bad("downscale is not in 1..8");
  if (firstBatch < 0) bad("first batch is not >= 0");
}

CameraMotionJudge::CameraMotionJudge(CameraMotionConfig config) : config_(config) {
  config_.validate();
}

void CameraMotionJudge::reset() {
  pending_.release();
  pendingQuads_.clear();
  reference_.release();
  referencePyramid_.clear();
  mask_.release();
  features_.clear();
  featuresPicked_ = false;
}

cv::Mat CameraMotionJudge::toWorkingGrey(const cv::Mat& image) const {
  const cv::Mat grey = toGrey(image);  // the detector's conversion (and its refusals)
  if (config_.downscale == 1) return grey.clone();
  cv::Mat small;
  cv::resize(grey, small, cv::Size(), 1.0 / config_.downscale, 1.0 / config_.downscale,
             cv::INTER_AREA);
  return small;
}

void CameraMotionJudge::setReference(const cv::Mat& image,
                                     const std::vector<std::array<cv::Point2d, 4>>& exclude,
                                     bool imageIsOwned) {
  // Kept as it is (a copy: the caller's frame buffer is reused); made into the working
  // reference only when a frame without the board needs it, so frames with the board pay for
  // a copy only.
  const cv::Mat grey = toGrey(image);
  pending_ = grey.data == image.data && !imageIsOwned ? grey.clone() : grey;
  pendingQuads_ = exclude;
  reference_.release();
  referencePyramid_.clear();
  mask_.release();
  features_.clear();
  featuresPicked_ = false;
}

void CameraMotionJudge::buildReference() {
  reference_ = toWorkingGrey(pending_);
  pending_.release();
  mask_ = cv::Mat(reference_.size(), CV_8U, cv::Scalar(255));
  const double s = 1.0 / config_.downscale;
  for (const auto& q : pendingQuads_) {
    cv::Point2d c(0, 0);
    for (const auto& p : q) c += 0.25 * p;
    std::vector<cv::Point> poly;
    for (const auto& p : q) {
      const cv::Point2d grown = c + (1 + 2 * config_.maskMargin) * (p - c);
      poly.emplace_back(int(std::lround(grown.x * s)), int(std::lround(grown.y * s)));
    }
    cv::fillConvexPoly(mask_, poly, cv::Scalar(0));
  }
  pendingQuads_.clear();
}

CameraMotion CameraMotionJudge::judge(const cv::Mat& image) {
  CameraMotion m;
  if (!pending_.empty()) buildReference();
  if (reference_.empty()) return m;
  if (!featuresPicked_) {
    // Picked once per reference, on the first frame that needs them: frames with the board in
    // view pay nothing.
    cv::goodFeaturesToTrack(reference_, features_, config_.maxFeatures, 0.01, 6.0, mask_, 5);
    featuresPicked_ = true;
  }
  m.features = int(features_.size());
  if (features_.size() < std::size_t(config_.minTracked)) return m;
  const cv::Mat now = toWorkingGrey(image);
  if (now.size() != reference_.size()) return m;
  // Pyramids built once per image: the reference's is kept for every frame it is judged
  // against, and each frame's serves both directions.
  const cv::Size window(11, 11);
  constexpr int kLevels = 3;
  if (referencePyramid_.empty())
    cv::buildOpticalFlowPyramid(reference_, referencePyramid_, window, kLevels);
  std::vector<cv::Mat> nowPyramid;
  cv::buildOpticalFlowPyramid(now, nowPyramid, window, kLevels);
  std::vector<double> shifts;
  // Corners [begin, end) tracked there and back; the shifts of those that came back go to
  // `shifts` (full-resolution px).
  auto track = [&](std::size_t begin, std::size_t end) {
    const std::vector<cv::Point2f> from(features_.begin() + std::ptrdiff_t(begin),
                                        features_.begin() + std::ptrdiff_t(end));
    std::vector<cv::Point2f> found, back;
    std::vector<unsigned char> status, backStatus;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(referencePyramid_, nowPyramid, from, found, status, err, window,
                             kLevels);
    // Forward-backward check: a corner under a hand or the tool now does not track back to
    // where it was, and is left out (what is left is the background that can still be seen).
    cv::calcOpticalFlowPyrLK(nowPyramid, referencePyramid_, found, back, backStatus, err, window,
                             kLevels);
    for (std::size_t i = 0; i < from.size(); ++i)
      if (status[i] && backStatus[i] && cv::norm(back[i] - from[i]) < 0.5)
        shifts.push_back(cv::norm(found[i] - from[i]) * config_.downscale);
  };
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const std::size_t batch = config_.firstBatch > 0
                                ? std::min(features_.size(), std::size_t(config_.firstBatch))
                                : features_.size();
  track(0, batch);
  if (batch < features_.size()) {
    if (shifts.size() >= std::max(std::size_t(config_.minTracked), (batch + 1) / 2) &&
        median(shifts) <= config_.maxShiftPx / 3) {
      m.tracked = int(shifts.size());
      m.judged = m.still = m.early = true;
      m.medianShiftPx = median(shifts);
      return m;
    }
    track(batch, features_.size());
  }
  m.tracked = int(shifts.size());
  m.judged = true;
  if (m.tracked < config_.minTracked ||
      double(m.tracked) < config_.minTrackedFraction * double(m.features)) {
    m.medianShiftPx = std::numeric_limits<double>::infinity();
    return m;
  }
  m.medianShiftPx = median(shifts);
  m.still = m.medianShiftPx <= config_.maxShiftPx;
  return m;
}

}  // namespace ps::tracking
