#include "terrain/camera.hpp"

#include <cmath>
#include <sstream>

#include "core/input_error.hpp"

namespace ps::terrain {

void Camera::validate() const {
  auto bad = [](const std::string& what) { throw core::InputError("degenerate camera: " + what); };
  if (!rotation.allFinite()) bad("rotation has non-finite entries");
  if (!eye.allFinite()) bad("eye position is not finite");
  if (!std::isfinite(fx) || !std::isfinite(fy) || fx <= 0 || fy <= 0) {
    std::ostringstream os;
    os << "focal lengths fx = " << fx << ", fy = " << fy << " must be positive";
    bad(os.str());
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) bad("principal point is not finite");
  if (width <= 0 || height <= 0)
    bad("viewport " + std::to_string(width) + "x" + std::to_string(height) + " is empty");
  const double orth =
      (rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-6 || rotation.determinant() < 0) {
    std::ostringstream os;
    os << "rotation is not a proper rotation (|R R^T - I| = " << orth
       << ", det = " << rotation.determinant() << ")";
    bad(os.str());
  }
}

Camera Camera::lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                      const Eigen::Vector3d& upHint, int width, int height, double horizontalFov) {
  const Eigen::Vector3d z = (target - eye).normalized();
  Eigen::Vector3d x = z.cross(upHint);  // right; y = z x x then points down on screen
  if (x.norm() < 1e-12) x = z.unitOrthogonal();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Camera c;
  c.rotation.row(0) = x.transpose();
  c.rotation.row(1) = y.transpose();
  c.rotation.row(2) = z.transpose();
  c.eye = eye;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * horizontalFov);
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  return c;
}

}  // namespace ps::terrain
