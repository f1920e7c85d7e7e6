#pragma once
// Where things go in the live window: the AR view at the left, whole and as large as the window
// allows; a column at the right for the panel and, below it, the overview inset, so that
// neither covers the markers or the planet the user is working on.
#include <algorithm>
#include <opencv2/core.hpp>

namespace ps::live {

// The column's width in window (display) units: the panel's widest row fits.
constexpr int kSideColumnWidth = 400;
// The overview inset's side in the column.
constexpr int kOverviewSide = 240;

// The window to open for a camera image of `camera` pixels: the view at 960x720 at least, and
// the column beside it.
inline cv::Size windowSizeFor(cv::Size camera) {
  return {std::max(camera.width, 960) + kSideColumnWidth, std::max(camera.height, 720)};
}

// The AR view's rectangle in a framebuffer of `fb` pixels whose window is `window` units wide
// (they differ on HiDPI screens): the camera's aspect, centred in what the column leaves.
inline cv::Rect arViewRect(cv::Size fb, int windowWidth, cv::Size camera) {
  const int column = windowWidth > 0 ? kSideColumnWidth * fb.width / windowWidth : 0;
  const int room = std::max(1, fb.width - column);
  const double fit = std::min(double(room) / camera.width, double(fb.height) / camera.height);
  const int w = int(camera.width * fit), h = int(camera.height * fit);
  return {(room - w) / 2, (fb.height - h) / 2, w, h};
}

}  // namespace ps::live
