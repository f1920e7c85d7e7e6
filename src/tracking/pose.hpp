#pragma once
// Marker poses from four corners: the planar square solver (IPPE_SQUARE through
// cv::solvePnPGeneric) gives two candidates (a square seen head-on is ambiguous: the "flip");
// the choice between them goes by reprojection error when one candidate is clearly better and
// by continuity with the previous pose otherwise.
//
// Frames: a marker's frame has its origin at the marker's centre, x toward its right edge, y
// toward its top edge and z out of the printed face (toward a camera that sees it); the camera
// frame is OpenCV's (x right, y down, z forward). Pose (R, t) maps marker to camera:
// X_cam = R X_marker + t.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <string>

#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"

namespace ps::tracking {

struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return R * x + t; }
  Pose inverse() const { return {R.transpose(), -(R.transpose() * t)}; }
  Pose operator*(const Pose& o) const { return {R * o.R, R * o.t + t}; }
  bool finite() const { return R.allFinite() && t.allFinite(); }

  // Rodrigues vector (axis * angle, radians).
  Eigen::Vector3d rvec() const;
  static Pose fromRvecTvec(const Eigen::Vector3d& rvec, const Eigen::Vector3d& tvec);
};

// Angle (radians) of the rotation between two rotation matrices.
double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

// Corners of a marker of edge `size` in its own frame, in detection order TL, TR, BR, BL (the
// order SOLVEPNP_IPPE_SQUARE requires).
std::array<Eigen::Vector3d, 4> markerObjectPoints(double size);

struct PoseCandidates {
  int count = 0;                    // 0 (solver failed or non-finite), 1 or 2
  std::array<Pose, 2> poses;        // sorted by reprojection error
  std::array<double, 2> rms{0, 0};  // RMS reprojection error (px)
};
// How candidates are polished. kOpenCv (cv::solvePnPRefineLM) is the single-marker path's, kept
// so that recordings replay bit for bit; kOwn (pose_refine.hpp) reaches the same minimum at
// about a tenth of the cost and is what marker sets use.
enum class PosePolish { kNone, kOpenCv, kOwn };
PoseCandidates solveMarkerPose(const std::array<cv::Point2d, 4>& corners, double size,
                               const CameraCalibration& calibration,
                               PosePolish polish = PosePolish::kOpenCv);
// The same candidates before the polish (IPPE_SQUARE's two and, with `globalSolver`, SQPNP's;
// the two best distinct ones): seeds for a pose that is polished over more points anyway (a
// marker set's).
PoseCandidates markerPoseSeeds(const std::array<cv::Point2d, 4>& corners, double size,
                               const CameraCalibration& calibration, bool globalSolver = true);

struct PoseChoice {
  bool valid = false;
  Pose pose;
  int candidate = 0;          // index into PoseCandidates::poses
  double ratio = 0;           // rms[1] / rms[0] (inf with one candidate)
  bool byContinuity = false;  // the ratio was below the threshold and a previous pose decided
};
// Picks the candidate with the lower error when rms[1] >= ratioThreshold * rms[0]; otherwise the
// one whose rotation is nearer to `previous` (when given), else the lower error.
PoseChoice choosePose(const PoseCandidates& c, const Pose* previous, double ratioThreshold);

// Projects points of the camera frame to pixels (with the calibration's distortion).
std::array<cv::Point2d, 4> projectMarker(const Pose& pose, double size,
                                         const CameraCalibration& calibration);

}  // namespace ps::tracking
