#include "tracking/plane_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "core/input_error.hpp"

namespace ps::tracking {

namespace {

const cv::Size kWindow(15, 15);
constexpr int kLevels = 3;

cv::Vec3d cvVec(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// Pixels to camera rays (undistorted, z = 1).
std::vector<cv::Point2f> rays(const std::vector<cv::Point2f>& px, const CameraCalibration& calib) {
  std::vector<cv::Point2f> out;
  if (!px.empty()) cv::undistortPoints(px, out, cv::Mat(calib.K), calib.distortion);
  return out;
}

template <class T>
void keep(std::vector<T>& v, const std::vector<unsigned char>& ok) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (ok[i]) v[n++] = v[i];
  v.resize(n);
}

}  // namespace

void PlaneTrackerConfig::validate() const {
  auto bad = [](const std::string& what) { throw core::InputError("plane tracker: " + what); };
  if (maxFeatures < 4) bad("max features is not >= 4");
  if (minInliers < 4) bad("min inliers is not >= 4");
  for (double v : {minDistancePx, ransacPx, maxRmsPx, maxJump, backPx, reanchorAgreePx})
    if (!(v > 0) || !std::isfinite(v)) bad("a distance or error bound is not > 0");
  if (!(minSpread >= 0 && minSpread <= 1)) bad("min spread is not in [0, 1]");
  if (reanchorEvery < 1) bad("re-anchor interval is not >= 1");
  if (!(maskMargin >= 0) || !std::isfinite(maskMargin)) bad("mask margin is not >= 0");
}

PlaneTracker::PlaneTracker(PlaneTrackerConfig config) : config_(config) {
  config_.validate();
}

void PlaneTracker::reset() {
  pending_.release();
  pendingExclude_.clear();
  anchorPyramid_.clear();
  prevPyramid_.clear();
  plane_.clear();
  anchor_.clear();
  prev_.clear();
  started_ = failed_ = false;
  frames_ = 0;
}

void PlaneTracker::setReference(const cv::Mat& grey, const Pose& board,
                                const std::vector<std::array<cv::Point2d, 4>>& exclude,
                                bool imageIsOwned, int quality) {
  if (!started_ && !pending_.empty() && quality < pendingQuality_ &&
      (board.t - pendingBoard_.t).norm() < 0.01 &&
      rotationAngle(board.R, pendingBoard_.R) < 2.0 * M_PI / 180)
    return;
  reset();
  pendingQuality_ = quality;
  // Kept as it is until a frame without the board needs it: frames with the board pay for a
  // copy only.
  pending_ = imageIsOwned ? grey : grey.clone();
  pendingBoard_ = board;
  pendingExclude_ = exclude;
}

void PlaneTracker::pick(const cv::Mat& grey, const std::vector<cv::Mat>& pyramid, const Pose& board,
                        const CameraCalibration& calib,
                        const std::vector<std::array<cv::Point2d, 4>>& exclude, bool asAnchor) {
  cv::Mat mask(grey.size(), CV_8U, cv::Scalar(255));
  for (const auto& q : exclude) {
    cv::Point2d c(0, 0);
    for (const auto& p : q) c += 0.25 * p;
    std::vector<cv::Point> poly;
    for (const auto& p : q) {
      const cv::Point2d grown = c + (1 + 2 * config_.maskMargin) * (p - c);
      poly.emplace_back(int(std::lround(grown.x)), int(std::lround(grown.y)));
    }
    cv::fillConvexPoly(mask, poly, cv::Scalar(0));
  }
  for (const auto& p : prev_)
    cv::circle(mask, cv::Point(int(std::lround(p.x)), int(std::lround(p.y))),
               int(config_.minDistancePx), cv::Scalar(0), cv::FILLED);
  const int wanted = asAnchor
                         ? config_.maxFeatures
                         : std::min(config_.maxFeatures - int(prev_.size()), int(prev_.size()));
  if (wanted <= 0) return;
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(grey, corners, wanted, 0.01, config_.minDistancePx, mask, 5);
  // Each corner's ray meets the board's plane (z = 0 in the board's frame).
  const Eigen::Vector3d n = board.R.col(2);
  const double nt = n.dot(board.t);
  const std::vector<cv::Point2f> r = rays(corners, calib);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Eigen::Vector3d d(r[i].x, r[i].y, 1.0);
    const double nd = n.dot(d);
    // Rays that graze the plane (the far table, the wall) put their corner nowhere useful.
    if (std::abs(nd) < 0.15 * d.norm() || nt / nd <= 0) continue;
    const Eigen::Vector3d x = board.R.transpose() * (nt / nd * d - board.t);
    plane_.emplace_back(float(x.x()), float(x.y()), 0.0f);
    prev_.push_back(corners[i]);
  }
  if (asAnchor) {
    anchorPyramid_ = pyramid;
    anchor_ = prev_;
  }
}

bool PlaneTracker::start(const CameraCalibration& calib) {
  if (pending_.empty()) return false;
  cv::buildOpticalFlowPyramid(pending_, anchorPyramid_, kWindow, kLevels);
  pick(pending_, anchorPyramid_, pendingBoard_, calib, pendingExclude_, true);
  prevPyramid_ = anchorPyramid_;
  last_ = pendingBoard_;
  pending_.release();
  pendingExclude_.clear();
  started_ = true;
  frames_ = 0;
  return true;
}

void PlaneTracker::reanchor(const std::vector<cv::Mat>& nowPyramid, PlaneTrack& r) {
  // From the anchor straight to the frame now, seeded where the chain put each corner: where the
  // two agree, the anchor's answer is kept (it has no chain of slips behind it).
  std::vector<cv::Point2f> direct = prev_, back;
  std::vector<unsigned char> status, backStatus;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(
      anchorPyramid_, nowPyramid, anchor_, direct, status, err, kWindow, kLevels,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01),
      cv::OPTFLOW_USE_INITIAL_FLOW);
  back = anchor_;
  cv::calcOpticalFlowPyrLK(
      nowPyramid, anchorPyramid_, direct, back, backStatus, err, kWindow, kLevels,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01),
      cv::OPTFLOW_USE_INITIAL_FLOW);
  for (std::size_t i = 0; i < prev_.size(); ++i)
    if (status[i] && backStatus[i] && cv::norm(back[i] - anchor_[i]) < config_.backPx &&
        cv::norm(direct[i] - prev_[i]) < config_.reanchorAgreePx) {
      prev_[i] = direct[i];
      r.reanchored = true;
    }
}

PlaneTrack PlaneTracker::track(const cv::Mat& grey, const CameraCalibration& calib,
                               const std::vector<std::array<cv::Point2d, 4>>& exclude) {
  PlaneTrack r;
  auto fail = [&](const std::string& why) {
    failed_ = true;
    r.why = why;
    return r;
  };
  if (failed_) return fail("lost since an earlier frame");
  if (!started_ && !start(calib)) return fail("no frame with the board to start from");
  if (grey.size() != anchorPyramid_[0].size()) return fail("the frame size changed");
  r.features = int(prev_.size());
  std::vector<cv::Mat> nowPyramid;
  cv::buildOpticalFlowPyramid(grey, nowPyramid, kWindow, kLevels);
  // Frame to frame, and back: a corner a hand covered or uncovered does not come back.
  std::vector<cv::Point2f> now, back;
  std::vector<unsigned char> status, backStatus;
  std::vector<float> err;
  if (!prev_.empty()) {
    cv::calcOpticalFlowPyrLK(prevPyramid_, nowPyramid, prev_, now, status, err, kWindow, kLevels);
    cv::calcOpticalFlowPyrLK(nowPyramid, prevPyramid_, now, back, backStatus, err, kWindow,
                             kLevels);
  }
  std::vector<unsigned char> ok(prev_.size());
  for (std::size_t i = 0; i < prev_.size(); ++i)
    ok[i] = status[i] && backStatus[i] && cv::norm(back[i] - prev_[i]) < config_.backPx;
  keep(now, ok);
  keep(plane_, ok);
  keep(anchor_, ok);
  prev_ = now;
  r.tracked = int(prev_.size());
  if (++frames_ % config_.reanchorEvery == 0 && !prev_.empty()) reanchor(nowPyramid, r);
  if (r.tracked < config_.minInliers) return fail("too few corners tracked");

  // The pose from the corners that agree on one: a homography (RANSAC) on undistorted rays
  // sorts them, Levenberg-Marquardt from the last pose polishes it on the inliers.
  const std::vector<cv::Point2f> nowRays = rays(prev_, calib);
  std::vector<cv::Point2f> onPlane;
  for (const auto& p : plane_) onPlane.emplace_back(p.x, p.y);
  std::vector<unsigned char> inlier;
  const double f = 0.5 * (calib.K(0, 0) + calib.K(1, 1));
  const cv::Mat H =
      cv::findHomography(onPlane, nowRays, cv::RANSAC, config_.ransacPx / f, inlier, 2000, 0.995);
  if (H.empty()) return fail("no homography");
  std::vector<cv::Point3f> obj;
  std::vector<cv::Point2f> img;
  for (std::size_t i = 0; i < inlier.size(); ++i)
    if (inlier[i]) obj.push_back(plane_[i]), img.push_back(prev_[i]);
  if (int(obj.size()) < config_.minInliers) return fail("too few corners agree on a plane");
  cv::Mat rvec(cvVec(last_.rvec())), tvec(cvVec(last_.t));
  cv::solvePnPRefineLM(obj, img, cv::Mat(calib.K), calib.distortion, rvec, tvec);
  const Pose pose =
      Pose::fromRvecTvec({rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)},
                         {tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)});
  if (!pose.finite()) return fail("no pose");
  // Inliers again by the polished pose.
  std::vector<cv::Point2f> reproj;
  cv::projectPoints(plane_, rvec, tvec, cv::Mat(calib.K), calib.distortion, reproj);
  std::vector<unsigned char> agree(plane_.size());
  double sq = 0;
  int n = 0;
  cv::Point2f lo(1e9f, 1e9f), hi(-1e9f, -1e9f);
  for (std::size_t i = 0; i < plane_.size(); ++i) {
    const double e = cv::norm(reproj[i] - prev_[i]);
    agree[i] = e <= config_.ransacPx;
    if (!agree[i]) continue;
    sq += e * e;
    ++n;
    lo = {std::min(lo.x, prev_[i].x), std::min(lo.y, prev_[i].y)};
    hi = {std::max(hi.x, prev_[i].x), std::max(hi.y, prev_[i].y)};
  }
  r.inliers = n;
  r.rmsPx = n > 0 ? std::sqrt(sq / n) : 0;
  if (n < config_.minInliers) return fail("too few corners agree with the pose");
  if (n > 0 && double(hi.x - lo.x) * (hi.y - lo.y) < config_.minSpread * grey.cols * grey.rows)
    return fail("the corners that agree cover too little of the image");
  if (r.rmsPx > config_.maxRmsPx) return fail("the corners fit the pose too loosely");
  if ((pose.t - last_.t).norm() > config_.maxJump) return fail("the pose jumped");
  // Outliers (a hand, the tool, a shadow) are dropped for good.
  keep(prev_, agree);
  keep(plane_, agree);
  keep(anchor_, agree);
  prevPyramid_ = nowPyramid;
  last_ = pose;
  if (int(prev_.size()) < config_.refillBelow) {
    // New corners where the camera sees now, put on the plane by this pose; the frame becomes
    // the anchor of every corner.
    pick(grey, nowPyramid, pose, calib, exclude, false);
    anchorPyramid_ = nowPyramid;
    anchor_ = prev_;
    r.refilled = true;
  }
  r.ok = true;
  r.board = pose;
  return r;
}

}  // namespace ps::tracking
