#pragma once
// Marker corners refined by aligning the marker's own image with the camera image.
//
// A detector's corners come from the four outer edges alone (AprilTag fits a line to each).
// Seen nearly head-on, a face's out-of-plane tilt shows only as a difference of a tenth of a
// pixel between opposite edges' lengths, so a 0.1 px corner error turns a 40 mm face by about
// 1.7 degrees: at a tool tip 105 mm away, several millimetres (docs/TRACKING.md). Every edge
// between the marker's cells carries the same information; aligning the canonical image with the
// image by a homography (enhanced correlation coefficient, OpenCV's findTransformECC: invariant
// to the marker's brightness and contrast) uses them all.
#include <opencv2/core.hpp>
#include <string>

#include "tracking/detector.hpp"

namespace ps::tracking {

struct TemplateRefineConfig {
  // Pixels per marker cell in the template: the work per iteration goes with its square. A
  // marker whose shortest edge spans fewer pixels a cell in the image is not refined.
  int cellPixels = 4;
  // How much of the white quiet zone around the black border the template holds, in cells:
  // half of the one cell every family's canonical image has, so a neighbouring face or marker
  // close to the border is not part of what is matched.
  double quietCells = 0.5;
  int maxIterations = 30;
  double epsilon = 1e-4;  // ECC's stop on the change of the correlation
  // The refined corners are kept only if none moved further than this from the detector's
  // (px): a correlation that ran off to another structure is dropped, not believed.
  double maxShiftPx = 1.5;
  int gaussianSize = 3;  // ECC's smoothing of template and image (odd, or 0 for none)
};

// Refines `detection`'s corners in place; false (and the corners unchanged) when the marker is
// too small (cellPixels) or too close to the image's border, the alignment does not converge or
// moves a corner more than maxShiftPx. `grey` is 8-bit, one channel.
bool refineCornersByTemplate(const cv::Mat& grey, const std::string& family, Detection& detection,
                             const TemplateRefineConfig& config = {});

}  // namespace ps::tracking
