#include "tracking/pose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>

#include "tracking/pose_refine.hpp"

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

namespace {

// Every candidate (IPPE_SQUARE's two and SQPNP's), polished by Levenberg-Marquardt when asked,
// with its RMS reprojection error; the two best distinct ones kept.
PoseCandidates markerCandidates(const std::array<cv::Point2d, 4>& corners, double size,
                                const CameraCalibration& calibration, PosePolish polish,
                                bool globalSolver) {
  PoseCandidates out;
  std::vector<cv::Point3d> object;
  for (const auto& p : markerObjectPoints(size)) object.emplace_back(p.x(), p.y(), p.z());
  const std::vector<cv::Point2d> image(corners.begin(), corners.end());
  for (const auto& p : image)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return out;
  // OpenCV 4.6's IPPE returns a wrong pose (up to a half turn off) for an exactly
  // fronto-parallel square, which synthetic video produces. So the candidates are IPPE_SQUARE's
  // two plus SQPNP's global minimum, each polished by Levenberg-Marquardt; the two best distinct
  // ones are kept.
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    cv::solvePnPGeneric(object, image, cv::Mat(calibration.K), calibration.distortion, rvecs, tvecs,
                        false, cv::SOLVEPNP_IPPE_SQUARE);
    if (globalSolver) {
      std::vector<cv::Mat> r2, t2;
      cv::solvePnPGeneric(object, image, cv::Mat(calibration.K), calibration.distortion, r2, t2,
                          false, cv::SOLVEPNP_SQPNP);
      rvecs.insert(rvecs.end(), r2.begin(), r2.end());
      tvecs.insert(tvecs.end(), t2.begin(), t2.end());
    }
  } catch (const cv::Exception&) {
    return out;
  }
  std::vector<std::pair<double, Pose>> found;
  for (std::size_t i = 0; i < rvecs.size(); ++i) {
    cv::Mat rv, tv;
    rvecs[i].convertTo(rv, CV_64F);
    tvecs[i].convertTo(tv, CV_64F);
    if (polish == PosePolish::kOwn) {
      Pose p = Pose::fromRvecTvec({rv.at<double>(0), rv.at<double>(1), rv.at<double>(2)},
                                  {tv.at<double>(0), tv.at<double>(1), tv.at<double>(2)});
      const double e = refinePose(object, image, calibration, p);
      if (std::isfinite(e) && p.t.z() > 0) found.emplace_back(e, p);
      continue;
    }
    if (polish == PosePolish::kOpenCv) {
      try {
        cv::solvePnPRefineLM(object, image, cv::Mat(calibration.K), calibration.distortion, rv, tv);
      } catch (const cv::Exception&) {
        continue;
      }
    }
    std::vector<cv::Point2d> projected;
    cv::projectPoints(object, rv, tv, cv::Mat(calibration.K), calibration.distortion, projected);
    double sum = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const cv::Point2d d = projected[k] - image[k];
      sum += d.dot(d);
    }
    const double e = std::sqrt(sum / 4);
    cv::Matx33d r;
    cv::Rodrigues(rv, r);
    Pose p;
    p.R = toEigen(r);
    p.t = {tv.at<double>(0), tv.at<double>(1), tv.at<double>(2)};
    if (!p.finite() || !std::isfinite(e) || p.t.z() <= 0) continue;
    found.emplace_back(e, p);
  }
  std::sort(found.begin(), found.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [e, p] : found) {
    bool duplicate = false;
    for (int i = 0; i < out.count; ++i) {
      duplicate |= rotationAngle(out.poses[std::size_t(i)].R, p.R) < 1e-4 &&
                   (out.poses[std::size_t(i)].t - p.t).norm() < 1e-6 * p.t.norm();
    }
    if (duplicate) continue;
    out.poses[std::size_t(out.count)] = p;
    out.rms[std::size_t(out.count)] = e;
    if (++out.count == 2) break;
  }
  return out;
}

}  // namespace

PoseCandidates solveMarkerPose(const std::array<cv::Point2d, 4>& corners, double size,
                               const CameraCalibration& calibration, PosePolish polish) {
  return markerCandidates(corners, size, calibration, polish, true);
}

PoseCandidates markerPoseSeeds(const std::array<cv::Point2d, 4>& corners, double size,
                               const CameraCalibration& calibration, bool globalSolver) {
  return markerCandidates(corners, size, calibration, PosePolish::kNone, globalSolver);
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
