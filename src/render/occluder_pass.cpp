#include "render/occluder_pass.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <vector>

#include "render/gl_program.hpp"
#include "render/projection.hpp"

namespace ps::render {

namespace {

// The camera image's own texel under the pixel (the background's, renderAR), or black.
constexpr const char* kOccluderFragment = R"(#version 330 core
uniform sampler2D image;
uniform int hasImage;
out vec4 colour;
void main() {
  if (hasImage == 0) {
    colour = vec4(0.0, 0.0, 0.0, 1.0);
    return;
  }
  ivec2 size = textureSize(image, 0);
  ivec2 texel = ivec2(int(gl_FragCoord.x), size.y - 1 - int(gl_FragCoord.y));
  colour = vec4(texelFetch(image, texel, 0).rgb, 1.0);
}
)";

}  // namespace

OccluderPass::OccluderPass() {
  program_ = linkProgram(kEyeRelativeVertex, kOccluderFragment);
  makePositionArray(vao_, buffer_);
}

OccluderPass::~OccluderPass() {
  glDeleteProgram(program_);
  glDeleteBuffers(1, &buffer_);
  glDeleteVertexArrays(1, &vao_);
}

void OccluderPass::draw(std::span<const Eigen::Vector3d> triangles, const terrain::Camera& camera,
                        const Eigen::Matrix4d& clip, unsigned image) {
  if (triangles.size() < 3) return;
  // Eye-relative in double first, then float: no large coordinate reaches float.
  std::vector<Eigen::Vector3f> rel;
  rel.reserve(triangles.size() - triangles.size() % 3);
  for (std::size_t i = 0; i + 2 < triangles.size(); i += 3)
    for (std::size_t k = 0; k < 3; ++k)
      rel.push_back((triangles[i + k] - camera.eye).cast<float>());
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, buffer_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(rel.size() * sizeof(Eigen::Vector3f)), rel.data(),
               GL_STREAM_DRAW);
  glUseProgram(program_);
  const auto m = columnMajor(clipFromEyeRelative(clip, camera.rotation, Eigen::Vector3d::Zero()));
  glUniformMatrix4fv(glGetUniformLocation(program_, "clipFromEyeRelative"), 1, GL_FALSE, m.data());
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, image);
  glUniform1i(glGetUniformLocation(program_, "image"), 0);
  glUniform1i(glGetUniformLocation(program_, "hasImage"), image != 0 ? 1 : 0);
  // A tool part nearer than the planet's near plane still hides it: depth clamped, not clipped
  // (it lands on the near plane, in front of every planet pixel).
  glEnable(GL_DEPTH_CLAMP);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);  // closed surfaces: the nearest face wins either way
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(rel.size()));
  glDisable(GL_DEPTH_CLAMP);
  glBindVertexArray(0);
  glUseProgram(0);
}

}  // namespace ps::render
