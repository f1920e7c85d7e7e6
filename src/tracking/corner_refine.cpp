#include "tracking/corner_refine.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <utility>
#include <vector>

#include "tracking/marker_family.hpp"

namespace ps::tracking {

namespace {

// The template's scale and how much of the quiet zone it holds. Measured on the board scenes
// (docs/TRACKING.md): 4 pixels a cell with half a cell of white aligns to 0.02 px (median worst
// corner); 8 pixels a cell does no better at four times the work, and templates with 1.5
// pixels of white or less on a side (a quarter cell, none) came out 0.5-0.75 px off.
constexpr int kCellPixels = 4;
constexpr int kQuietPixels = 2;

}  // namespace

CornerRefiner::CornerRefiner(std::string family, TemplateRefineConfig config)
    : family_(std::move(family)), info_(familyInfo(family_)), config_(config) {}

const cv::Mat& CornerRefiner::markerTemplate(int id) {
  auto it = templates_.find(id);
  if (it != templates_.end()) return it->second;
  const FamilyInfo& info = info_;
  cv::Mat full;
  cv::resize(markerCells(family_, id), full, {}, kCellPixels, kCellPixels, cv::INTER_NEAREST);
  const int start = info.edgeOffset * kCellPixels - kQuietPixels;
  const int side = info.edgeCells * kCellPixels + 2 * kQuietPixels;
  return templates_.emplace(id, full(cv::Rect(start, start, side, side)).clone()).first->second;
}

bool CornerRefiner::refine(const cv::Mat& grey, Detection& detection) {
  CV_Assert(grey.type() == CV_8UC1);
  const FamilyInfo& info = info_;
  const cv::Mat& templ = markerTemplate(detection.id);
  // Cell boundaries lie between pixels (pixel centres at integers, as the detector's corners).
  const double lo = kQuietPixels - 0.5;
  const double hi = kQuietPixels + info.edgeCells * kCellPixels - 0.5;
  const std::vector<cv::Point2f> templCorners = {{float(lo), float(lo)},
                                                 {float(hi), float(lo)},
                                                 {float(hi), float(hi)},
                                                 {float(lo), float(hi)}};
  const TemplateRefineConfig& config = config_;

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
  if (shortest < info.edgeCells * kCellPixels) return false;
  const double cellPx = std::max(x1 - x0, y1 - y0) / info.edgeCells;
  const double margin = 0.5 * cellPx + config.maxShiftPx + config.gaussianSize + 2;
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

bool refineCornersByTemplate(const cv::Mat& grey, const std::string& family, Detection& detection,
                             const TemplateRefineConfig& config) {
  return CornerRefiner(family, config).refine(grey, detection);
}

}  // namespace ps::tracking
