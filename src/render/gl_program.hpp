#pragma once
// Shader programs and matrices for the renderer's passes (planet_renderer.cpp,
// atmosphere_passes.cpp). Needs a current OpenGL 3.3 context.
#include <Eigen/Core>
#include <array>

namespace ps::render {

// A vertex shader for positions relative to the camera (in the planet frame), attribute 0,
// through the uniform clipFromEyeRelative: the lines' and the occluders' passes.
inline constexpr const char* kEyeRelativeVertex = R"(#version 330 core
layout(location = 0) in vec3 position;  // relative to the camera (planet frame)
uniform mat4 clipFromEyeRelative;
void main() { gl_Position = clipFromEyeRelative * vec4(position, 1.0); }
)";

// Compiles and links a vertex and a fragment shader. Throws std::runtime_error with the
// compiler's or linker's log.
unsigned linkProgram(const char* vertexSource, const char* fragmentSource);

// A new vertex array and array buffer, the buffer's tightly packed vec3s as attribute 0 (what
// kEyeRelativeVertex reads). Leaves the buffer bound and no vertex array.
void makePositionArray(unsigned& vertexArray, unsigned& buffer);

// A matrix as OpenGL's uniforms take it (column-major floats).
std::array<float, 16> columnMajor(const Eigen::Matrix4d& m);

}  // namespace ps::render
