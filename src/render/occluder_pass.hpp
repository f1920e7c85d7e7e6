#pragma once
// What stands between the camera and the planet in the AR view (the tracked tool: its solid and
// stick, tracking/tool_shape.hpp), drawn before the planet so that the planet is hidden exactly
// where it is nearer the camera. Its triangles write depth, through the planet's own clip
// planes (clamped, not clipped: a tool nearer than the planet's near plane still hides it), and
// the camera image's own pixels as colour, so that the board shadow and the atmosphere rim drawn
// before them do not paint over the tool either. docs/RENDERING.md, "The tool's depth pass".
#include <Eigen/Core>
#include <span>

#include "terrain/camera.hpp"

namespace ps::render {

class OccluderPass {
 public:
  // Needs a current OpenGL 3.3 context; throws std::runtime_error if the shader does not build.
  OccluderPass();
  ~OccluderPass();
  OccluderPass(const OccluderPass&) = delete;
  OccluderPass& operator=(const OccluderPass&) = delete;

  // `triangles`: 3 points per triangle, planet frame (planet metres), as the renderer's cursor.
  // `image`: the texture holding the camera image (0: black, as the cleared background), drawn
  // as the background is (top row first, one texel per pixel). Leaves depth testing on
  // (GL_LESS), depth writes on, no program bound.
  void draw(std::span<const Eigen::Vector3d> triangles, const terrain::Camera& camera,
            const Eigen::Matrix4d& clip, unsigned image);

 private:
  unsigned program_ = 0, vao_ = 0, buffer_ = 0;
};

}  // namespace ps::render
