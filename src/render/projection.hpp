#pragma once
// Cameras for rendering: OpenCV's pinhole (x right, y down, z forward; pixel centres at integer
// coordinates) turned into OpenGL clip space, and the AR camera built from a tracked planet
// marker. The renderer reads the framebuffer back top row first, so a point that OpenCV
// projects to pixel (u, v) is drawn at image pixel (u, v) exactly (the alignment test checks it).
#include <Eigen/Core>
#include <optional>

#include "terrain/camera.hpp"
#include "terrain/terrain.hpp"

namespace ps::render {

// Clip-space matrix for points in the camera frame (OpenCV axes), from the pinhole's
// intrinsics and image size, with depth mapped from [near, far] to [-1, 1].
Eigen::Matrix4d clipFromCamera(const terrain::Camera& camera, double nearZ, double farZ);

// projection * [rotation | 0] * translate(offset): the matrix the renderer applies to points
// given relative to `offset` + camera eye (planet frame), e.g. a mesh's eye-relative positions
// with offset = mesh.eye - camera.eye.
Eigen::Matrix4d clipFromEyeRelative(const Eigen::Matrix4d& clipFromCamera,
                                    const Eigen::Matrix3d& rotation, const Eigen::Vector3d& offset);

// What the GPU computes for one vertex, in float as the shader does: the pixel (OpenCV
// convention) of eye-relative position p under the float copy of `clipFromEyeRelative`.
// nullopt behind the camera.
std::optional<Eigen::Vector2d> pixelThroughFloatPath(const Eigen::Matrix4d& clipFromEyeRelative,
                                                     const Eigen::Vector3f& p, int width,
                                                     int height);

// Near and far planes that hold everything of the planet the camera can see: far at the far
// side of the planet's bounding sphere, near at half the distance to its surface shell (never
// below far * 1e-6, keeping depth resolution).
struct DepthRange {
  double nearZ = 1, farZ = 2;
};
DepthRange depthRangeFor(const terrain::Camera& camera, const terrain::Terrain& planet);

// The AR camera in the planet frame (planet metres): `planetInCamera` is the planet frame's
// pose in the camera frame in marker-world metres (SceneTracker::planetFromMarker), `scale` the
// planet metres per marker-world metre, K and size the calibrated intrinsics.
terrain::Camera arCamera(const Eigen::Matrix3d& rotationCameraFromPlanet,
                         const Eigen::Vector3d& planetOriginInCamera, double scale,
                         const Eigen::Matrix3d& K, int width, int height);

}  // namespace ps::render
