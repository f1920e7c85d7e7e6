#pragma once
// The live app's window: GLFW with an OpenGL 3.3 core context, Dear ImGui on it, a texture
// ImGui can draw, and the window's pixels read back for a screenshot. Only live_app uses it;
// nothing here knows about planets or sessions.
#include <imgui.h>

#include <opencv2/core.hpp>

struct GLFWwindow;

namespace ps::live {

// GLFW, initialised for the lifetime of the app. Throws std::runtime_error without a display.
class GlfwLibrary {
 public:
  GlfwLibrary();
  ~GlfwLibrary();
  GlfwLibrary(const GlfwLibrary&) = delete;
  GlfwLibrary& operator=(const GlfwLibrary&) = delete;
};

// A window with a current OpenGL 3.3 core context (vsync on unless `vsync` is false). Throws
// std::runtime_error when none can be made.
class Window {
 public:
  Window(int width, int height, const char* title, bool vsync);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  GLFWwindow* handle() const { return window_; }
  bool closeRequested() const;
  void requestClose();
  cv::Size framebufferSize() const;
  cv::Size windowSize() const;  // in display units (the framebuffer's on most screens)
  // Binds framebuffer 0 with the whole window as viewport, cleared to the backdrop colour.
  void clear(cv::Size framebuffer) const;
  void swapBuffers();
  // The back buffer as BGR, top row first.
  cv::Mat pixels(cv::Size framebuffer) const;

 private:
  GLFWwindow* window_ = nullptr;
};

// Dear ImGui with its GLFW and OpenGL 3 back ends, for one window.
class ImGuiLayer {
 public:
  explicit ImGuiLayer(Window& window);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;
  void newFrame();
  // Draws this frame's ImGui windows over whatever framebuffer 0 holds.
  void render(cv::Size framebuffer);
};

// An image ImGui can draw (the overview inset). It is drawn by the renderer every Nth frame
// only, so it cannot be a blit of the renderer's framebuffer (which holds the AR view the rest
// of the time): the image the renderer returns goes into this texture, drawn every frame.
class Texture {
 public:
  Texture();
  ~Texture();
  Texture(const Texture&) = delete;
  Texture& operator=(const Texture&) = delete;
  void update(const cv::Mat& bgr);
  bool valid() const { return valid_; }
  ImTextureID imgui() const;

 private:
  unsigned id_ = 0;
  cv::Mat rgb_;
  bool valid_ = false;
};

// The GL_RENDERER string of the current context, for the start-up line.
const char* glRendererName();

}  // namespace ps::live
