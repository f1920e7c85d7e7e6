#pragma once
// What the live app's two loops (the recovery question at start, then sculpting) draw into:
// the window with its ImGui panel, the renderer, the input and the camera's last image.
#include <atomic>
#include <opencv2/core.hpp>
#include <optional>
#include <span>

#include "live/frame_input.hpp"
#include "live/gl_window.hpp"
#include "live/live_app.hpp"
#include "render/planet_renderer.hpp"

namespace ps::live {

struct Shell {
  Window& window;
  ImGuiLayer& imgui;
  render::PlanetRenderer& renderer;
  FrameInput& input;
  const LiveSettings& settings;
  LiveResult& result;
  const std::atomic<bool>& interrupted;  // Ctrl-C: save and leave
  const cv::Size camera = input.size();
  cv::Mat image = cv::Mat::zeros(camera, CV_8UC3);
  cv::Mat lastView =
      cv::Mat();  // the AR view present() drew last (BGR, read back from the renderer)

  bool running() const;
  // Draws the camera image (and the planet's mesh, when there is one) into the window, the
  // camera's aspect fitted in and centred; returns the window's framebuffer size.
  cv::Size present(const terrain::Terrain& planet, const terrain::Mesh& mesh,
                   const terrain::Camera& cam, const render::RenderStyle& style,
                   const std::optional<render::Cursor>& cursor,
                   std::span<const Eigen::Vector3d> occluders = {});
  // The panel over the view, the screenshot on the last scripted frame, and the swap.
  void finish(cv::Size fb);
};

}  // namespace ps::live
