#include "render/gl_program.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <stdexcept>
#include <string>

namespace ps::render {

namespace {

GLuint compileShader(GLenum type, const char* source) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetShaderInfoLog(s, GLsizei(log.size()), nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error(std::string("renderer: shader does not compile: ") + log.data());
  }
  return s;
}

}  // namespace

unsigned linkProgram(const char* vertexSource, const char* fragmentSource) {
  const GLuint v = compileShader(GL_VERTEX_SHADER, vertexSource);
  const GLuint f = compileShader(GL_FRAGMENT_SHADER, fragmentSource);
  const GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetProgramInfoLog(p, GLsizei(log.size()), nullptr, log.data());
    glDeleteProgram(p);
    throw std::runtime_error(std::string("renderer: program does not link: ") + log.data());
  }
  return p;
}

void makePositionArray(unsigned& vertexArray, unsigned& buffer) {
  glGenVertexArrays(1, &vertexArray);
  glGenBuffers(1, &buffer);
  glBindVertexArray(vertexArray);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glBindVertexArray(0);
}

std::array<float, 16> columnMajor(const Eigen::Matrix4d& m) {
  std::array<float, 16> a{};
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a[std::size_t(4 * c + r)] = float(m(r, c));
  return a;
}

}  // namespace ps::render
