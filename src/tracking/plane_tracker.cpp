#include "tracking/plane_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "core/input_error.hpp"

namespace ps::tracking {

namespace {

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
  if (gridColumns < 1 || gridRows < 1) bad("the corner grid is not at least 1 x 1");
  if (downscale < 1) bad("downscale is not >= 1");
  if (windowPx < 3) bad("the LK window is not >= 3 px");
  if (pyramidMaxLevel < 0) bad("the pyramid's max level is not >= 0");
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

cv::Mat PlaneTracker::working(const cv::Mat& grey) const {
  if (config_.downscale == 1) return grey;
  cv::Mat out;
  cv::resize(grey, out, cv::Size(grey.cols / config_.downscale, grey.rows / config_.downscale), 0,
             0, cv::INTER_AREA);
  return out;
}

std::vector<cv::Mat> PlaneTracker::pyramid(const cv::Mat& work) const {
  std::vector<cv::Mat> out;
  cv::buildOpticalFlowPyramid(work, out, cv::Size(config_.windowPx, config_.windowPx),
                              config_.pyramidMaxLevel);
  return out;
}

std::vector<cv::Point2f> PlaneTracker::full(const std::vector<cv::Point2f>& work) const {
  // Pixel centres: working pixel i covers full-resolution pixels [i * s, (i + 1) * s).
  std::vector<cv::Point2f> out;
  out.reserve(work.size());
  for (const auto& p : work)
    out.emplace_back(float((p.x + 0.5) * scaleX_ - 0.5), float((p.y + 0.5) * scaleY_ - 0.5));
  return out;
}

void PlaneTracker::pick(const cv::Mat& work, const std::vector<cv::Mat>& pyramid, const Pose& board,
                        const CameraCalibration& calib,
                        const std::vector<std::array<cv::Point2d, 4>>& exclude, bool asAnchor) {
  cv::Mat mask(work.size(), CV_8U, cv::Scalar(255));
  for (const auto& q : exclude) {
    cv::Point2d c(0, 0);
    for (const auto& p : q) c += 0.25 * p;
    std::vector<cv::Point> poly;
    for (const auto& p : q) {
      const cv::Point2d grown = c + (1 + 2 * config_.maskMargin) * (p - c);
      poly.emplace_back(int(std::lround((grown.x + 0.5) / scaleX_ - 0.5)),
                        int(std::lround((grown.y + 0.5) / scaleY_ - 0.5)));
    }
    cv::fillConvexPoly(mask, poly, cv::Scalar(0));
  }
  const double minDistance = config_.minDistancePx / config_.downscale;
  for (const auto& p : prev_)
    cv::circle(mask, cv::Point(int(std::lround(p.x)), int(std::lround(p.y))),
               int(std::ceil(minDistance)), cv::Scalar(0), cv::FILLED);
  const int wanted = asAnchor
                         ? config_.maxFeatures
                         : std::min(config_.maxFeatures - int(prev_.size()), int(prev_.size()));
  if (wanted <= 0) return;
  // Spread over the grid: the strongest of each cell first (goodFeaturesToTrack sorts them), its
  // share of the count; what textureless cells leave goes to the strongest of the rest.
  std::vector<cv::Point2f> candidates, corners;
  cv::goodFeaturesToTrack(work, candidates, 4 * wanted, 0.01, minDistance, mask, 5);
  const int cells = config_.gridColumns * config_.gridRows;
  const int share = (wanted + cells - 1) / cells;
  std::vector<int> inCell(std::size_t(cells), 0);
  std::vector<unsigned char> taken(candidates.size(), 0);
  for (std::size_t i = 0; i < candidates.size() && int(corners.size()) < wanted; ++i) {
    const int cx = std::clamp(int(candidates[i].x * config_.gridColumns / work.cols), 0,
                              config_.gridColumns - 1);
    const int cy =
        std::clamp(int(candidates[i].y * config_.gridRows / work.rows), 0, config_.gridRows - 1);
    if (inCell[std::size_t(cy * config_.gridColumns + cx)]++ >= share) continue;
    corners.push_back(candidates[i]);
    taken[i] = 1;
  }
  for (std::size_t i = 0; i < candidates.size() && int(corners.size()) < wanted; ++i)
    if (!taken[i]) corners.push_back(candidates[i]);
  // Each corner's ray meets the board's plane (z = 0 in the board's frame).
  const Eigen::Vector3d n = board.R.col(2);
  const double nt = n.dot(board.t);
  const std::vector<cv::Point2f> r = rays(full(corners), calib);
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
  const cv::Mat work = working(pending_);
  fullSize_ = pending_.size();
  scaleX_ = double(pending_.cols) / work.cols;
  scaleY_ = double(pending_.rows) / work.rows;
  anchorPyramid_ = pyramid(work);
  pick(work, anchorPyramid_, pendingBoard_, calib, pendingExclude_, true);
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
  const cv::Size window(config_.windowPx, config_.windowPx);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  cv::calcOpticalFlowPyrLK(anchorPyramid_, nowPyramid, anchor_, direct, status, err, window,
                           config_.pyramidMaxLevel, stop, cv::OPTFLOW_USE_INITIAL_FLOW);
  back = anchor_;
  cv::calcOpticalFlowPyrLK(nowPyramid, anchorPyramid_, direct, back, backStatus, err, window,
                           config_.pyramidMaxLevel, stop, cv::OPTFLOW_USE_INITIAL_FLOW);
  const double backPx = config_.backPx / config_.downscale;
  const double agreePx = config_.reanchorAgreePx / config_.downscale;
  for (std::size_t i = 0; i < prev_.size(); ++i)
    if (status[i] && backStatus[i] && cv::norm(back[i] - anchor_[i]) < backPx &&
        cv::norm(direct[i] - prev_[i]) < agreePx) {
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
  if (grey.size() != fullSize_) return fail("the frame size changed");
  r.features = int(prev_.size());
  const cv::Mat work = working(grey);
  const std::vector<cv::Mat> nowPyramid = pyramid(work);
  // Frame to frame, and back: a corner a hand covered or uncovered does not come back.
  std::vector<cv::Point2f> now, back;
  std::vector<unsigned char> status, backStatus;
  std::vector<float> err;
  const cv::Size window(config_.windowPx, config_.windowPx);
  if (!prev_.empty()) {
    cv::calcOpticalFlowPyrLK(prevPyramid_, nowPyramid, prev_, now, status, err, window,
                             config_.pyramidMaxLevel);
    cv::calcOpticalFlowPyrLK(nowPyramid, prevPyramid_, now, back, backStatus, err, window,
                             config_.pyramidMaxLevel);
  }
  const double backPx = config_.backPx / config_.downscale;
  std::vector<unsigned char> ok(prev_.size());
  for (std::size_t i = 0; i < prev_.size(); ++i)
    ok[i] = status[i] && backStatus[i] && cv::norm(back[i] - prev_[i]) < backPx;
  keep(now, ok);
  keep(plane_, ok);
  keep(anchor_, ok);
  prev_ = now;
  r.tracked = int(prev_.size());
  if (++frames_ % config_.reanchorEvery == 0 && !prev_.empty()) reanchor(nowPyramid, r);
  if (r.tracked < config_.minInliers) return fail("too few corners tracked");

  // The pose from the corners that agree on one: a homography (RANSAC) on undistorted rays
  // sorts them, Levenberg-Marquardt from the last pose polishes it on the inliers.
  const std::vector<cv::Point2f> nowPx = full(prev_);
  const std::vector<cv::Point2f> nowRays = rays(nowPx, calib);
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
    if (inlier[i]) obj.push_back(plane_[i]), img.push_back(nowPx[i]);
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
    const double e = cv::norm(reproj[i] - nowPx[i]);
    agree[i] = e <= config_.ransacPx;
    if (!agree[i]) continue;
    sq += e * e;
    ++n;
    lo = {std::min(lo.x, nowPx[i].x), std::min(lo.y, nowPx[i].y)};
    hi = {std::max(hi.x, nowPx[i].x), std::max(hi.y, nowPx[i].y)};
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
    pick(work, nowPyramid, pose, calib, exclude, false);
    anchorPyramid_ = nowPyramid;
    anchor_ = prev_;
    r.refilled = true;
  }
  r.ok = true;
  r.board = pose;
  return r;
}

}  // namespace ps::tracking
