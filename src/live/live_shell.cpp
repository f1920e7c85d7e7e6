#include "live/live_shell.hpp"

#include <algorithm>

#include "io/heightmap_export.hpp"

namespace ps::live {

bool Shell::running() const {
  return !window.closeRequested() && !interrupted &&
         (settings.frames == 0 || result.frames < settings.frames);
}

cv::Size Shell::present(const terrain::Terrain& planet, const terrain::Mesh& mesh,
                        const terrain::Camera& cam, const render::RenderStyle& style,
                        const std::optional<render::Cursor>& cursor) {
  renderer.renderAR(image, planet, mesh, cam, style, cursor);
  const cv::Size fb = window.framebufferSize();
  window.clear(fb);
  const double fit = std::min(double(fb.width) / camera.width, double(fb.height) / camera.height);
  const int vw = int(camera.width * fit), vh = int(camera.height * fit);
  renderer.present((fb.width - vw) / 2, (fb.height - vh) / 2, vw, vh);
  return fb;
}

void Shell::finish(cv::Size fb) {
  imgui.render(fb);
  if (!settings.screenshot.empty() && settings.frames > 0 && result.frames + 1 == settings.frames)
    io::writePngAtomically(window.pixels(fb), settings.screenshot);
  window.swapBuffers();
}

}  // namespace ps::live
