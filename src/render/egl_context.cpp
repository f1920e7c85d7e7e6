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
  }() + "); an EGL driver is needed (Mesa's: libegl-mesa0, libgl1-mesa-dri; or a GPU's)";
}

bool initialised(EGLDisplay d) {
  EGLint major = 0, minor = 0;
  return d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor);
}

// The first display that initialises: Mesa's surfaceless platform, then each EGL device (how
// NVIDIA's driver offers its GPUs without a window system), then the default display.
EGLDisplay openDisplay() {
  auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  auto queryDevices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (getPlatformDisplay) {
    EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (initialised(d)) return d;
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    if (queryDevices && queryDevices(16, devices, &n)) {
      for (EGLint i = 0; i < n; ++i) {
        d = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (initialised(d)) return d;
      }
    }
  }
  const EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  return initialised(d) ? d : EGL_NO_DISPLAY;
}
}  // namespace

EglContext::EglContext() {
  const EGLDisplay d = openDisplay();
  if (d == EGL_NO_DISPLAY)
    throw std::runtime_error(eglError("eglInitialize (surfaceless, device and default display)"));
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
