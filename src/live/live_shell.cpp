#include "live/live_shell.hpp"

#include <algorithm>

#include "io/heightmap_export.hpp"
#include "live/window_layout.hpp"

namespace ps::live {

bool Shell::running() const {
  return !window.closeRequested() && !interrupted &&
         (settings.frames == 0 || result.frames < settings.frames);
}

cv::Size Shell::present(const terrain::Terrain& planet, const terrain::Mesh& mesh,
                        const terrain::Camera& cam, const render::RenderStyle& style,
                        const std::optional<render::Cursor>& cursor,
                        std::span<const Eigen::Vector3d> occluders) {
  lastView = renderer.renderAR(image, planet, mesh, cam, style, cursor, occluders);
  const cv::Size fb = window.framebufferSize();
  window.clear(fb);
  // GL's window coordinates start at the bottom: the rectangle's y from there.
  const cv::Rect view = arViewRect(fb, window.windowSize().width, {camera.width, camera.height});
  renderer.present(view.x, fb.height - view.y - view.height, view.width, view.height);
  return fb;
}

void Shell::finish(cv::Size fb) {
  imgui.render(fb);
  if (!settings.screenshot.empty() && settings.frames > 0 && result.frames + 1 == settings.frames)
    io::writePngAtomically(window.pixels(fb), settings.screenshot);
  window.swapBuffers();
}

}  // namespace ps::live
