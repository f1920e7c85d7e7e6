#include "tracking/pose_refine.hpp"

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>

namespace ps::tracking {

namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

constexpr double kInf = std::numeric_limits<double>::infinity();

// OpenCV's camera model (cv::projectPoints) up to its rational radial terms: k1 k2 p1 p2 k3 k4
// k5 k6. Like projectPoints, the skew K(0, 1) is not used.
struct Lens {
  double fx = 1, fy = 1, cx = 0, cy = 0;
  std::array<double, 8> k{};  // k1 k2 p1 p2 k3 k4 k5 k6

  // False when the calibration has terms this model lacks (thin prism, tilt).
  bool read(const CameraCalibration& c) {
    fx = c.K(0, 0), fy = c.K(1, 1), cx = c.K(0, 2), cy = c.K(1, 2);
    const cv::Mat d = c.distortion;
    const std::size_t n = d.empty() ? 0 : d.total();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) return false;
    if (n > 0 && (d.type() != CV_64F || !d.isContinuous())) return false;
    const double* v = n > 0 ? d.ptr<double>() : nullptr;
    for (std::size_t i = 0; i < n; ++i) {
      if (i < k.size())
        k[i] = v[i];
      else if (v[i] != 0.0)
        return false;
    }
    return true;
  }

  // Pixel of the camera-frame point X, and d(pixel)/dX; false behind the camera.
  bool project(const Eigen::Vector3d& X, Eigen::Vector2d& px,
               Eigen::Matrix<double, 2, 3>& J) const {
    if (!(X.z() > 0)) return false;
    const double iz = 1.0 / X.z(), x = X.x() * iz, y = X.y() * iz;
    const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
    const double num = 1 + k[0] * r2 + k[1] * r4 + k[4] * r6;
    const double den = 1 + k[5] * r2 + k[6] * r4 + k[7] * r6;
    const double radial = num / den;
    const double dnum = k[0] + 2 * k[1] * r2 + 3 * k[4] * r4;  // d num / d r2
    const double dden = k[5] + 2 * k[6] * r2 + 3 * k[7] * r4;
    const double dradial = (dnum * den - num * dden) / (den * den);
    const double p1 = k[2], p2 = k[3];
    const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
    const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
    px = {fx * xd + cx, fy * yd + cy};
    // d(xd, yd) / d(x, y), with d r2 / dx = 2x.
    Eigen::Matrix2d D;
    D(0, 0) = radial + 2 * x * x * dradial + 2 * p1 * y + 6 * p2 * x;
    D(0, 1) = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y;
    D(1, 0) = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y;
    D(1, 1) = radial + 2 * y * y * dradial + 6 * p1 * y + 2 * p2 * x;
    Eigen::Matrix<double, 2, 3> dxy;
    dxy << iz, 0, -x * iz, 0, iz, -y * iz;
    J = Eigen::Vector2d(fx, fy).asDiagonal() * D * dxy;
    return true;
  }
};

Eigen::Matrix3d cross(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

// Squared residuals summed, and the normal equations of the step: the rotation is perturbed on
// the left (R <- exp(w) R) and the translation added to, so d X / d w = -[R P]x.
bool evaluate(const Lens& lens, const std::vector<cv::Point3d>& object,
              const std::vector<cv::Point2d>& image, const Pose& pose, double& cost, Matrix6& A,
              Vector6& g) {
  cost = 0;
  A.setZero();
  g.setZero();
  Eigen::Vector2d px;
  Eigen::Matrix<double, 2, 3> J;
  Eigen::Matrix<double, 2, 6> Jp;
  for (std::size_t i = 0; i < object.size(); ++i) {
    const Eigen::Vector3d RP = pose.R * Eigen::Vector3d(object[i].x, object[i].y, object[i].z);
    if (!lens.project(RP + pose.t, px, J)) return false;
    const Eigen::Vector2d r = px - Eigen::Vector2d(image[i].x, image[i].y);
    Jp.leftCols<3>() = -J * cross(RP);
    Jp.rightCols<3>() = J;
    cost += r.squaredNorm();
    A.selfadjointView<Eigen::Upper>().rankUpdate(Jp.transpose());
    g.noalias() += Jp.transpose() * r;
  }
  A = A.selfadjointView<Eigen::Upper>();
  return std::isfinite(cost) && A.allFinite();
}

Pose stepped(const Pose& p, const Vector6& d) {
  const Eigen::Vector3d w = d.head<3>();
  const double angle = w.norm();
  const Eigen::Matrix3d turn = angle > 0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix()
                                         : Eigen::Matrix3d::Identity();
  return {turn * p.R, p.t + d.tail<3>()};
}

double refineWithOpenCv(const std::vector<cv::Point3d>& object,
                        const std::vector<cv::Point2d>& image, const CameraCalibration& calib,
                        Pose& pose) {
  const Eigen::Vector3d r0 = pose.rvec();
  cv::Mat rv = (cv::Mat_<double>(3, 1) << r0.x(), r0.y(), r0.z());
  cv::Mat tv = (cv::Mat_<double>(3, 1) << pose.t.x(), pose.t.y(), pose.t.z());
  try {
    cv::solvePnPRefineLM(object, image, cv::Mat(calib.K), calib.distortion, rv, tv);
  } catch (const cv::Exception&) {
    return kInf;
  }
  std::vector<cv::Point2d> projected;
  cv::projectPoints(object, rv, tv, cv::Mat(calib.K), calib.distortion, projected);
  double sum = 0;
  for (std::size_t k = 0; k < projected.size(); ++k) {
    const cv::Point2d d = projected[k] - image[k];
    sum += d.dot(d);
  }
  pose = Pose::fromRvecTvec({rv.at<double>(0), rv.at<double>(1), rv.at<double>(2)},
                            {tv.at<double>(0), tv.at<double>(1), tv.at<double>(2)});
  const double e = std::sqrt(sum / double(projected.size()));
  return pose.finite() && std::isfinite(e) ? e : kInf;
}

}  // namespace

double refinePose(const std::vector<cv::Point3d>& object, const std::vector<cv::Point2d>& image,
                  const CameraCalibration& calibration, Pose& pose) {
  if (object.empty() || object.size() != image.size() || !pose.finite()) return kInf;
  Lens lens;
  if (!lens.read(calibration)) return refineWithOpenCv(object, image, calibration, pose);
  double cost = 0;
  Matrix6 A;
  Vector6 g;
  if (!evaluate(lens, object, image, pose, cost, A, g)) return kInf;
  // Marquardt's damping: each step solves (A + lambda diag(A)) d = -g; a step that lowers the
  // error is kept and the damping eased, one that does not is retried more damped. The loop
  // ends where the pose stops changing at double precision (a few steps from a seed that is
  // within the basin, which every caller's seed is).
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 100 && cost > 0; ++iteration) {
    Matrix6 M = A;
    M.diagonal() *= 1 + lambda;
    const Vector6 d = M.ldlt().solve(-g);
    if (!d.allFinite()) break;
    const bool tiny = d.head<3>().norm() < 1e-14 && d.tail<3>().norm() < 1e-14 * pose.t.norm();
    const Pose trial = stepped(pose, d);
    double trialCost = 0;
    Matrix6 trialA;
    Vector6 trialG;
    if (evaluate(lens, object, image, trial, trialCost, trialA, trialG) && trialCost < cost) {
      const bool settled = tiny || cost - trialCost <= 1e-15 * cost;
      pose = trial;
      cost = trialCost;
      A = trialA;
      g = trialG;
      lambda = std::max(lambda * 0.1, 1e-12);
      if (settled) break;
    } else {
      if (tiny) break;  // at the minimum to rounding
      lambda *= 10;
      if (lambda > 1e12) break;
    }
  }
  const double rms = std::sqrt(cost / double(object.size()));
  return pose.finite() && std::isfinite(rms) ? rms : kInf;
}

}  // namespace ps::tracking
