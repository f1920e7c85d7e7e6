#pragma once
// Shader programs and matrices for the renderer's passes (planet_renderer.cpp,
// atmosphere_passes.cpp). Needs a current OpenGL 3.3 context.
#include <Eigen/Core>
#include <array>

namespace ps::render {

// Compiles and links a vertex and a fragment shader. Throws std::runtime_error with the
// compiler's or linker's log.
unsigned linkProgram(const char* vertexSource, const char* fragmentSource);

// A matrix as OpenGL's uniforms take it (column-major floats).
std::array<float, 16> columnMajor(const Eigen::Matrix4d& m);

}  // namespace ps::render
