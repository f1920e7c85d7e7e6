#pragma once
// A headless OpenGL 3.3 core context through EGL (no display, no window): Mesa's surfaceless
// platform (llvmpipe on machines without a GPU), else an EGL device (NVIDIA's driver), else the
// default display. One per thread that renders; made current on construction. Rendering goes to
// framebuffer objects (render/planet_renderer.hpp).
#include <string>

namespace ps::render {

class EglContext {
 public:
  // Throws std::runtime_error saying which EGL step failed (no EGL library, no display that
  // initialises, no OpenGL 3.3 core).
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  void makeCurrent() const;
  std::string renderer() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string version() const;   // GL_VERSION

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
};

// True when a headless context can be made here (tests skip with a message otherwise).
bool headlessGlAvailable(std::string* why = nullptr);

}  // namespace ps::render
