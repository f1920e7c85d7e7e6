#include "tracking/pose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>

namespace ps::tracking {

namespace {
Eigen::Matrix3d toEigen(const cv::Matx33d& m) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
  return r;
}
}  // namespace

Eigen::Vector3d Pose::rvec() const {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

Pose Pose::fromRvecTvec(const Eigen::Vector3d& rvec, const Eigen::Vector3d& tvec) {
  const double angle = rvec.norm();
  Pose p;
  p.R = angle > 0 ? Eigen::AngleAxisd(angle, rvec / angle).toRotationMatrix()
                  : Eigen::Matrix3d::Identity();
  p.t = tvec;
  return p;
}

double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Quaterniond qa(a), qb(b);
  return qa.angularDistance(qb);
}

std::array<Eigen::Vector3d, 4> markerObjectPoints(double size) {
  const double h = 0.5 * size;
  return {Eigen::Vector3d(-h, h, 0), Eigen::Vector3d(h, h, 0), Eigen::Vector3d(h, -h, 0),
          Eigen::Vector3d(-h, -h, 0)};
}

PoseCandidates solveMarkerPose(const std::array<cv::Point2d, 4>& corners, double size,
                               const CameraCalibration& calibration) {
  PoseCandidates out;
  std::vector<cv::Point3d> object;
  for (const auto& p : markerObjectPoints(size)) object.emplace_back(p.x(), p.y(), p.z());
  const std::vector<cv::Point2d> image(corners.begin(), corners.end());
  for (const auto& p : image)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return out;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat errors;
  try {
    cv::solvePnPGeneric(object, image, cv::Mat(calibration.K), calibration.distortion, rvecs, tvecs,
                        false, cv::SOLVEPNP_IPPE_SQUARE, cv::noArray(), cv::noArray(), errors);
  } catch (const cv::Exception&) {
    return out;
  }
  std::array<std::pair<double, Pose>, 2> found;
  int n = 0;
  for (std::size_t i = 0; i < rvecs.size() && n < 2; ++i) {
    cv::Matx33d r;
    cv::Rodrigues(rvecs[i], r);
    Pose p;
    p.R = toEigen(r);
    cv::Mat t;
    tvecs[i].convertTo(t, CV_64F);
    p.t = {t.at<double>(0), t.at<double>(1), t.at<double>(2)};
    double e = errors.empty() ? 0.0 : errors.at<double>(int(i));
    if (!p.finite() || !std::isfinite(e) || p.t.z() <= 0) continue;
    found[std::size_t(n++)] = {e, p};
  }
  if (n == 2 && found[1].first < found[0].first) std::swap(found[0], found[1]);
  out.count = n;
  for (int i = 0; i < n; ++i) {
    out.poses[std::size_t(i)] = found[std::size_t(i)].second;
    out.rms[std::size_t(i)] = found[std::size_t(i)].first;
  }
  return out;
}

PoseChoice choosePose(const PoseCandidates& c, const Pose* previous, double ratioThreshold) {
  PoseChoice ch;
  if (c.count == 0) return ch;
  ch.valid = true;
  ch.pose = c.poses[0];
  if (c.count == 1) {
    ch.ratio = std::numeric_limits<double>::infinity();
    return ch;
  }
  ch.ratio = c.rms[1] / std::max(c.rms[0], 1e-12);
  if (ch.ratio >= ratioThreshold || !previous) return ch;
  ch.byContinuity = true;
  const double a0 = rotationAngle(c.poses[0].R, previous->R);
  const double a1 = rotationAngle(c.poses[1].R, previous->R);
  if (a1 < a0) {
    ch.candidate = 1;
    ch.pose = c.poses[1];
  }
  return ch;
}

std::array<cv::Point2d, 4> projectMarker(const Pose& pose, double size,
                                         const CameraCalibration& calibration) {
  std::vector<cv::Point3d> cam;
  for (const auto& p : markerObjectPoints(size)) {
    const Eigen::Vector3d x = pose.apply(p);
    cam.emplace_back(x.x(), x.y(), x.z());
  }
  std::vector<cv::Point2d> px;
  cv::projectPoints(cam, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calibration.K),
                    calibration.distortion, px);
  return {px[0], px[1], px[2], px[3]};
}

}  // namespace ps::tracking
