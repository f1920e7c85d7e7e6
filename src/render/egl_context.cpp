#include "render/egl_context.hpp"

#define EGL_EGLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>

#include <stdexcept>

namespace ps::render {

namespace {
std::string eglError(const char* step) {
  return std::string("headless OpenGL: ") + step + " failed (EGL error 0x" + [] {
    char b[16];
    std::snprintf(b, sizeof b, "%04x", unsigned(eglGetError()));
    return std::string(b);
  }() + "); Mesa's EGL (libegl-mesa0, libgl1-mesa-dri) is needed";
}
}  // namespace

EglContext::EglContext() {
  auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  EGLDisplay d = EGL_NO_DISPLAY;
  if (getPlatformDisplay)
    d = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (d == EGL_NO_DISPLAY)
    throw std::runtime_error(eglError("eglGetPlatformDisplayEXT(surfaceless)"));
  EGLint major = 0, minor = 0;
  if (!eglInitialize(d, &major, &minor)) throw std::runtime_error(eglError("eglInitialize"));
  display_ = d;
  if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error(eglError("eglBindAPI(OpenGL)"));
  const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                  EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint n = 0;
  // Surfaceless contexts need no config on Mesa; pass one when there is one.
  eglChooseConfig(d, configAttribs, &config, 1, &n);
  const EGLint contextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                   3,
                                   EGL_CONTEXT_MINOR_VERSION,
                                   3,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                   EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                   EGL_NONE};
  context_ =
      eglCreateContext(d, n > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, contextAttribs);
  if (context_ == EGL_NO_CONTEXT) {
    eglTerminate(d);
    throw std::runtime_error(eglError("eglCreateContext(OpenGL 3.3 core)"));
  }
  makeCurrent();
}

EglContext::~EglContext() {
  if (display_) {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_) eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
}

void EglContext::makeCurrent() const {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
    throw std::runtime_error(eglError("eglMakeCurrent"));
}

std::string EglContext::renderer() const {
  const auto* s = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return s ? s : "";
}

std::string EglContext::version() const {
  const auto* s = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return s ? s : "";
}

bool headlessGlAvailable(std::string* why) {
  try {
    EglContext c;
    return true;
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return false;
  }
}

}  // namespace ps::render
