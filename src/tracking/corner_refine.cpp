#include "tracking/corner_refine.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <vector>

#include "tracking/marker_family.hpp"

namespace ps::tracking {

bool refineCornersByTemplate(const cv::Mat& grey, const std::string& family, Detection& detection,
                             const TemplateRefineConfig& config) {
  CV_Assert(grey.type() == CV_8UC1);
  const FamilyInfo info = familyInfo(family);
  const int p = config.cellPixels;
  const double q = std::clamp(config.quietCells, 0.0, double(info.edgeOffset));
  // The template: the canonical image at p pixels a cell, cut to the black border and q cells
  // of the quiet zone around it.
  cv::Mat full;
  cv::resize(markerCells(family, detection.id), full, {}, p, p, cv::INTER_NEAREST);
  const int start = int(std::lround((info.edgeOffset - q) * p));
  const int side = int(std::lround((info.edgeCells + 2 * q) * p));
  const cv::Mat templ = full(cv::Rect(start, start, side, side));
  // Cell boundaries lie between pixels (pixel centres at integers, as the detector's corners).
  const double lo = info.edgeOffset * p - 0.5 - start;
  const double hi = (info.edgeOffset + info.edgeCells) * p - 0.5 - start;
  const std::vector<cv::Point2f> templCorners = {{float(lo), float(lo)},
                                                 {float(hi), float(lo)},
                                                 {float(hi), float(hi)},
                                                 {float(lo), float(hi)}};

  // The image around the marker, with room for the quiet zone, the smoothing and the shift.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& c : detection.corners) {
    x0 = std::min(x0, c.x);
    y0 = std::min(y0, c.y);
    x1 = std::max(x1, c.x);
    y1 = std::max(y1, c.y);
  }
  // Shorter than the template's cells in the image, the image would be sampled finer than it
  // holds detail, and the alignment comes out worse than the edge fit (the board sweep's faces
  // under 32 px: 0.10 px against 0.07 px, median worst corner).
  double shortest = 1e300;
  for (std::size_t k = 0; k < 4; ++k)
    shortest = std::min(shortest, cv::norm(detection.corners[k] - detection.corners[(k + 1) % 4]));
  if (shortest < info.edgeCells * p) return false;
  const double cellPx = std::max(x1 - x0, y1 - y0) / info.edgeCells;
  const double margin = q * cellPx + config.maxShiftPx + config.gaussianSize + 2;
  const cv::Rect roi(cv::Point(int(std::floor(x0 - margin)), int(std::floor(y0 - margin))),
                     cv::Point(int(std::ceil(x1 + margin)) + 1, int(std::ceil(y1 + margin)) + 1));
  if ((roi & cv::Rect(0, 0, grey.cols, grey.rows)) != roi) return false;
  std::vector<cv::Point2f> seen(4);
  for (std::size_t k = 0; k < 4; ++k)
    seen[k] =
        cv::Point2f(float(detection.corners[k].x - roi.x), float(detection.corners[k].y - roi.y));
  cv::Mat warp;
  cv::getPerspectiveTransform(templCorners, seen).convertTo(warp, CV_32F);
  try {
    cv::findTransformECC(templ, grey(roi), warp, cv::MOTION_HOMOGRAPHY,
                         cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                          config.maxIterations, config.epsilon),
                         cv::noArray(), config.gaussianSize);
  } catch (const cv::Exception&) {
    return false;  // no convergence: the detector's corners stand
  }
  std::vector<cv::Point2f> refined;
  cv::perspectiveTransform(templCorners, refined, warp);
  std::array<cv::Point2d, 4> out;
  for (std::size_t k = 0; k < 4; ++k) {
    if (!std::isfinite(refined[k].x) || !std::isfinite(refined[k].y)) return false;
    out[k] = cv::Point2d(refined[k].x + roi.x, refined[k].y + roi.y);
    if (cv::norm(out[k] - detection.corners[k]) > config.maxShiftPx) return false;
  }
  detection.corners = out;
  return true;
}

}  // namespace ps::tracking
