#include "render/atmosphere_passes.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "render/atmosphere_shaders.hpp"
#include "render/gl_program.hpp"
#include "render/projection.hpp"

namespace ps::render {

namespace {

// Clip space for a pass's quad, whose corners lie between `nearest` and `farthest` along the
// camera's axis (farthest > 0). Depth is neither tested nor written: the planes only need to
// hold the quad's visible part, with room to spare (a far plane at the corners themselves would
// clip them in float; near / far >= 1e-4 keeps the depth mapping well within float).
Eigen::Matrix4d overlayClip(const terrain::Camera& camera, double nearest, double farthest) {
  const double farZ = 2 * farthest;
  const double nearZ = std::max(farZ * 1e-4, 0.5 * nearest);
  return clipFromEyeRelative(clipFromCamera(camera, nearZ, farZ), camera.rotation,
                             Eigen::Vector3d::Zero());
}

// Blending and depth as the passes need them, and back as renderAR keeps them.
struct OverlayState {
  OverlayState(GLenum source, GLenum destination) {
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(source, destination);
  }
  ~OverlayState() {
    glDisable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ZERO);
    glDepthMask(GL_TRUE);
    glUseProgram(0);
    glBindVertexArray(0);
  }
  OverlayState(const OverlayState&) = delete;
  OverlayState& operator=(const OverlayState&) = delete;
};

}  // namespace

AtmospherePasses::AtmospherePasses() {
  shadowProgram_ = linkProgram(kBoardShadowVertex, kBoardShadowFragment);
  rimProgram_ = linkProgram(kRimVertex, kRimFragment);
  glGenVertexArrays(1, &quadVao_);
  glGenBuffers(1, &quadBuffer_);
  glBindVertexArray(quadVao_);
  glBindBuffer(GL_ARRAY_BUFFER, quadBuffer_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(1);
  glBindVertexArray(0);
  if (glGetError() != GL_NO_ERROR) throw std::runtime_error("renderer: OpenGL setup failed");
}

AtmospherePasses::~AtmospherePasses() {
  glDeleteProgram(shadowProgram_);
  glDeleteProgram(rimProgram_);
  glDeleteBuffers(1, &quadBuffer_);
  glDeleteVertexArrays(1, &quadVao_);
}

void AtmospherePasses::drawBoardShadow(const terrain::Camera& camera, double R,
                                       const Eigen::Vector3d& sun, const Eigen::Vector3d& up,
                                       const BoardShadowLook& look) {
  const double sunUp = sun.dot(up);
  if (!(R > 0) || !(sunUp > 1e-6)) return;  // no sun above the board: no shadow on it
  // The board's axes: `away` the sun's direction on the board, turned away from it.
  Eigen::Vector3d away = -(sun - sunUp * up);
  away = away.norm() > 1e-9 ? away.normalized() : up.unitOrthogonal();
  const Eigen::Vector3d across = up.cross(away);
  // The shadow's centre lies tan(zenith) R from the contact point; its far end 1 / cos(zenith)
  // times `outer` beyond it: the quad holds that, out to `reach`.
  const double horizontal = std::sqrt(std::max(0.0, 1 - sunUp * sunUp));
  const double margin = 1.05 * look.outer;
  const double far = std::min(horizontal / sunUp + margin / sunUp, look.reach);
  const Eigen::Vector3d foot = -up;  // / R
  const std::array<Eigen::Vector2d, 4> corners = {
      Eigen::Vector2d(-margin, -margin), Eigen::Vector2d(far, -margin),
      Eigen::Vector2d(-margin, margin), Eigen::Vector2d(far, margin)};
  std::array<float, 24> vertices{};
  double nearest = std::numeric_limits<double>::infinity(), farthest = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d q = foot + corners[i].x() * away + corners[i].y() * across;
    const Eigen::Vector3d rel = R * q - camera.eye;  // in double, then float: no jitter
    const double z = (camera.rotation * rel).z();
    nearest = std::min(nearest, z);
    farthest = std::max(farthest, z);
    for (int k = 0; k < 3; ++k) {
      vertices[6 * i + std::size_t(k)] = float(rel[k]);
      vertices[6 * i + 3 + std::size_t(k)] = float(q[k]);
    }
  }
  if (!(farthest > 0)) return;  // the board's patch is behind the camera
  const Eigen::Matrix4d clip = overlayClip(camera, nearest, farthest);
  const OverlayState state(GL_ZERO, GL_SRC_COLOR);  // video x (1 - strength * shadow)
  glUseProgram(shadowProgram_);
  const auto m = columnMajor(clip);
  glUniformMatrix4fv(glGetUniformLocation(shadowProgram_, "clipFromEyeRelative"), 1, GL_FALSE,
                     m.data());
  glUniform3f(glGetUniformLocation(shadowProgram_, "sun"), float(sun.x()), float(sun.y()),
              float(sun.z()));
  glUniform3f(glGetUniformLocation(shadowProgram_, "foot"), float(foot.x()), float(foot.y()),
              float(foot.z()));
  glUniform1f(glGetUniformLocation(shadowProgram_, "inner"), float(look.inner));
  glUniform1f(glGetUniformLocation(shadowProgram_, "outer"), float(look.outer));
  glUniform1f(glGetUniformLocation(shadowProgram_, "strength"), float(look.strength));
  glUniform1f(glGetUniformLocation(shadowProgram_, "fadeStart"), float(0.6 * look.reach));
  glUniform1f(glGetUniformLocation(shadowProgram_, "fadeEnd"), float(look.reach));
  glBindVertexArray(quadVao_);
  glBindBuffer(GL_ARRAY_BUFFER, quadBuffer_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(sizeof vertices), vertices.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
}

void AtmospherePasses::drawRim(const terrain::Camera& camera, double R, const Eigen::Vector3d& sun,
                               const RimLook& look) {
  if (!(R > 0)) return;
  const Eigen::Vector3d eye = camera.eye / R;
  const double D = eye.norm(), outer = 1 + look.width;
  if (!(D > outer)) return;  // inside the atmosphere: no rim to see
  // The glow's silhouette cone from the eye (half-angle asin(outer / D)) cut by the plane through
  // the centre across the view: a circle of radius D tan(angle), held by a square of that
  // half-side. Only the pixels inside it run the fragment shader.
  const Eigen::Vector3d axis = -eye / D;
  const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  const double half = 1.02 * D * outer / std::sqrt(D * D - outer * outer);
  std::array<float, 24> vertices{};
  double nearest = std::numeric_limits<double>::infinity(), farthest = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const double a = (i & 1) ? half : -half, b = (i & 2) ? half : -half;
    const Eigen::Vector3d rel = R * (a * e1 + b * e2) - camera.eye;  // double, then float
    const double z = (camera.rotation * rel).z();
    nearest = std::min(nearest, z);
    farthest = std::max(farthest, z);
    for (int k = 0; k < 3; ++k) vertices[6 * i + std::size_t(k)] = float(rel[k]);
  }
  if (!(farthest > 0)) return;
  const Eigen::Matrix4d clip = overlayClip(camera, nearest, farthest);
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = camera.fx;
  K(1, 1) = camera.fy;
  K(0, 2) = camera.cx;
  K(1, 2) = camera.cy;
  const Eigen::Matrix3d rayFromPixel = camera.rotation.transpose() * K.inverse();
  std::array<float, 9> ray{};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) ray[std::size_t(3 * c + r)] = float(rayFromPixel(r, c));
  const OverlayState state(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(rimProgram_);
  const auto m = columnMajor(clip);
  glUniformMatrix4fv(glGetUniformLocation(rimProgram_, "clipFromEyeRelative"), 1, GL_FALSE,
                     m.data());
  glUniformMatrix3fv(glGetUniformLocation(rimProgram_, "rayFromPixel"), 1, GL_FALSE, ray.data());
  glUniform3f(glGetUniformLocation(rimProgram_, "eye"), float(eye.x()), float(eye.y()),
              float(eye.z()));
  glUniform1f(glGetUniformLocation(rimProgram_, "imageHeight"), float(camera.height));
  glUniform3f(glGetUniformLocation(rimProgram_, "sun"), float(sun.x()), float(sun.y()),
              float(sun.z()));
  glUniform3f(glGetUniformLocation(rimProgram_, "glow"), look.colour.x(), look.colour.y(),
              look.colour.z());
  glUniform1f(glGetUniformLocation(rimProgram_, "peak"), float(look.peak));
  glUniform1f(glGetUniformLocation(rimProgram_, "width"), float(look.width));
  glBindVertexArray(quadVao_);
  glBindBuffer(GL_ARRAY_BUFFER, quadBuffer_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(sizeof vertices), vertices.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
}

}  // namespace ps::render
