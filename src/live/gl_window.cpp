#include "live/gl_window.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>

#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace ps::live {

namespace {

std::string gGlfwError;
void onGlfwError(int code, const char* what) {
  gGlfwError = "GLFW error " + std::to_string(code) + ": " + (what ? what : "");
}

}  // namespace

GlfwLibrary::GlfwLibrary() {
  glfwSetErrorCallback(onGlfwError);
  if (!glfwInit())
    throw std::runtime_error("live: cannot start GLFW (no display? " + gGlfwError + ")");
}

GlfwLibrary::~GlfwLibrary() {
  glfwTerminate();
}

Window::Window(int width, int height, const char* title, bool vsync) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(width, height, title, nullptr, nullptr);
  if (!window_)
    throw std::runtime_error("live: cannot open a window with OpenGL 3.3 core (" + gGlfwError +
                             ")");
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(vsync ? 1 : 0);
}

Window::~Window() {
  glfwDestroyWindow(window_);
}

bool Window::closeRequested() const {
  return glfwWindowShouldClose(window_);
}

void Window::requestClose() {
  glfwSetWindowShouldClose(window_, GLFW_TRUE);
}

cv::Size Window::framebufferSize() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return {w, h};
}

cv::Size Window::windowSize() const {
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  return {w, h};
}

void Window::clear(cv::Size framebuffer) const {
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, framebuffer.width, framebuffer.height);
  glClearColor(0.02f, 0.02f, 0.03f, 1);
  glClear(GL_COLOR_BUFFER_BIT);
}

void Window::swapBuffers() {
  glfwSwapBuffers(window_);
}

cv::Mat Window::pixels(cv::Size framebuffer) const {
  cv::Mat rgba(framebuffer, CV_8UC4), bgr, flipped;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, framebuffer.width, framebuffer.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data);
  cv::cvtColor(rgba, bgr, cv::COLOR_RGBA2BGR);
  cv::flip(bgr, flipped, 0);
  return flipped;
}

ImGuiLayer::ImGuiLayer(Window& window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window.handle(), true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

ImGuiLayer::~ImGuiLayer() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

void ImGuiLayer::newFrame() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void ImGuiLayer::render(cv::Size framebuffer) {
  ImGui::Render();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);  // the window, whatever the renderer left bound
  glViewport(0, 0, framebuffer.width, framebuffer.height);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

Texture::Texture() {
  glGenTextures(1, &id_);
}

Texture::~Texture() {
  glDeleteTextures(1, &id_);
}

void Texture::update(const cv::Mat& bgr) {
  cv::cvtColor(bgr, rgb_, cv::COLOR_BGR2RGB);
  glBindTexture(GL_TEXTURE_2D, id_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, rgb_.cols, rgb_.rows, 0, GL_RGB, GL_UNSIGNED_BYTE,
               rgb_.data);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glBindTexture(GL_TEXTURE_2D, 0);
  valid_ = true;
}

ImTextureID Texture::imgui() const {
  return reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(id_));
}

const char* glRendererName() {
  return reinterpret_cast<const char*>(glGetString(GL_RENDERER));
}

}  // namespace ps::live
