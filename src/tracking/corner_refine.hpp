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
#include <map>
#include <opencv2/core.hpp>
#include <string>

#include "tracking/detector.hpp"
#include "tracking/marker_family.hpp"

namespace ps::tracking {

struct TemplateRefineConfig {
  int maxIterations = 30;
  double epsilon = 1e-4;  // ECC's stop on the change of the correlation
  // The refined corners are kept only if none moved further than this from the detector's
  // (px): a correlation that ran off to another structure is dropped, not believed.
  double maxShiftPx = 1.5;
  int gaussianSize = 3;  // ECC's smoothing of template and image (odd, or 0 for none)
};

// Refines detections of one family, each id's template (the canonical image cut to its border
// and half a cell of the quiet zone, 4 pixels a cell) made once and kept, not every frame.
class CornerRefiner {
 public:
  explicit CornerRefiner(std::string family, TemplateRefineConfig config = {});
  // Refines `detection`'s corners in place; false (and the corners unchanged) when the marker
  // spans fewer than 4 pixels a cell (the template's scale: a finer template than the image
  // aligns worse than the edge fit), lies too close to the image's border, the alignment does
  // not converge or moves a corner more than maxShiftPx. `grey` is 8-bit, one channel.
  bool refine(const cv::Mat& grey, Detection& detection);

 private:
  const cv::Mat& markerTemplate(int id);
  std::string family_;
  FamilyInfo info_;  // throws for an unknown family at construction, not at the first frame
  TemplateRefineConfig config_;
  std::map<int, cv::Mat> templates_;
};

// One detection with a refiner made for it (tests, still images).
bool refineCornersByTemplate(const cv::Mat& grey, const std::string& family, Detection& detection,
                             const TemplateRefineConfig& config = {});

}  // namespace ps::tracking
