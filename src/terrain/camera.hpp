#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ps::terrain {

// A pinhole camera in the planet's frame, OpenCV convention (x right, y down, z forward).
// rotation maps planet-frame vectors into the camera frame; eye is the camera centre.
struct Camera {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  double fx = 1000, fy = 1000, cx = 640, cy = 360;
  int width = 1280, height = 720;

  // Throws core::InputError naming the bad field: non-finite values, fx or fy <= 0, an empty
  // viewport, or a rotation that is not orthonormal.
  void validate() const;

  Eigen::Vector3d toCamera(const Eigen::Vector3d& world) const { return rotation * (world - eye); }
  // Pixel coordinates of a camera-frame point (z > 0).
  Eigen::Vector2d project(const Eigen::Vector3d& cam) const {
    return {fx * cam.x() / cam.z() + cx, fy * cam.y() / cam.z() + cy};
  }

  // A camera at `eye` looking at `target`, with `upHint` roughly up on screen, and a horizontal
  // field of view in radians.
  static Camera lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                       const Eigen::Vector3d& upHint, int width, int height, double horizontalFov);

  bool operator==(const Camera&) const = default;
};

}  // namespace ps::terrain
