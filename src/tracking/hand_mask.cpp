#include "tracking/hand_mask.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/input_error.hpp"

namespace ps::tracking {

namespace {

void requireHandMask(bool ok, const std::string& field, const std::string& rule, double value) {
  if (!ok)
    throw core::InputError("hand mask: " + field + " " + rule + " (got " +
                           core::exactNumber(value) + ")");
}

cv::Mat disc(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * radius + 1, 2 * radius + 1});
}

}  // namespace

void HandMaskConfig::validate() const {
  appearance.validate();
  requireHandMask(std::isfinite(silhouetteMargin) && silhouetteMargin >= 0 && silhouetteMargin <= 1,
                  "silhouette_margin", "is not in [0, 1]", silhouetteMargin);
  requireHandMask(std::isfinite(ringFraction) && ringFraction > 0 && ringFraction <= 2,
                  "ring_fraction", "is not in (0, 2]", ringFraction);
  requireHandMask(std::isfinite(strongScore) && strongScore >= 1, "strong_score", "is not >= 1",
                  strongScore);
  requireHandMask(minAreaFraction >= 0 && minAreaFraction < 1, "min_area_fraction",
                  "is not in [0, 1)", minAreaFraction);
  requireHandMask(minInteriorAreaFraction >= 0 && minInteriorAreaFraction < 1,
                  "min_interior_area_fraction", "is not in [0, 1)", minInteriorAreaFraction);
  requireHandMask(openPx >= 0 && openPx <= 20, "open_px", "is not in 0..20", openPx);
  requireHandMask(closePx >= 0 && closePx <= 20, "close_px", "is not in 0..20", closePx);
  requireHandMask(std::isfinite(featherPx) && featherPx >= 0 && featherPx <= 50, "feather_px",
                  "is not in [0, 50]", featherPx);
}

namespace {

// Where the sphere's silhouette can be: the projection of its bounding cube (the whole image
// when the cube reaches behind the camera).
cv::Rect silhouetteBounds(cv::Size size, const cv::Matx33d& K, const Eigen::Vector3d& c,
                          double radius) {
  const cv::Rect image(0, 0, size.width, size.height);
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d p =
        c + radius * Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    if (p.z() <= 1e-6) return image;
    const double u = K(0, 0) * p.x() / p.z() + K(0, 2), v = K(1, 1) * p.y() / p.z() + K(1, 2);
    x0 = std::min(x0, u), x1 = std::max(x1, u), y0 = std::min(y0, v), y1 = std::max(y1, v);
  }
  const auto clampTo = [](double v, int hi) { return int(std::clamp(v, 0.0, double(hi))); };
  const int l = clampTo(std::floor(x0) - 1, size.width), r = clampTo(std::ceil(x1) + 2, size.width);
  const int t = clampTo(std::floor(y0) - 1, size.height),
            b = clampTo(std::ceil(y1) + 2, size.height);
  return cv::Rect(l, t, r - l, b - t) & image;
}

}  // namespace

namespace {

// Silhouettes of concentric spheres (radii ascending) drawn into `out` (CV_8U at the image's
// size, 255 inside), in one pass over the largest one's bounds.
void drawSilhouettes(const std::vector<cv::Mat*>& out, const std::vector<double>& radii,
                     const cv::Matx33d& K, const Eigen::Vector3d& c) {
  const double cc = c.squaredNorm();
  if (!(c.z() > 0) || !(radii.back() > 0) || !std::isfinite(cc)) return;
  const cv::Rect box = silhouetteBounds(out.back()->size(), K, c, radii.back());
  const double fx = K(0, 0), fy = K(1, 1), cx = K(0, 2), cy = K(1, 2);
  std::vector<double> k;  // |c|² - r² per sphere
  for (const double r : radii) k.push_back(cc - r * r);
  for (int v = box.y; v < box.y + box.height; ++v) {
    const double dy = (v - cy) / fy;
    for (int u = box.x; u < box.x + box.width; ++u) {
      const double dx = (u - cx) / fx;
      // The ray t·d meets the sphere when (d·c)² >= |d|²(|c|² - r²), ahead of the camera.
      const double dc = dx * c.x() + dy * c.y() + c.z();
      const double dd = dx * dx + dy * dy + 1.0;
      if (!(dc > 0)) continue;
      for (std::size_t i = out.size(); i-- > 0;) {
        if (!(radii[i] > 0) || dc * dc < dd * k[i]) break;  // outside this one, so the smaller
        out[i]->at<uchar>(v, u) = 255;
      }
    }
  }
}

// The grown square `r` by `by` texels on each side, except on the sides where it reaches the
// edge of `square` (none to read beyond there), within it.
cv::Rect grownWithin(const cv::Rect& r, int by, const cv::Rect& square) {
  return cv::Rect(r.x - by, r.y - by, r.width + 2 * by, r.height + 2 * by) & square;
}

// `r` shrunk by `by` on the sides that are not on the edge of `square`.
cv::Rect shrunkWithin(const cv::Rect& r, int by, const cv::Rect& square) {
  const int l = r.x > square.x ? r.x + by : r.x, t = r.y > square.y ? r.y + by : r.y;
  const int rr = r.br().x < square.br().x ? r.br().x - by : r.br().x;
  const int b = r.br().y < square.br().y ? r.br().y - by : r.br().y;
  return rr > l && b > t ? cv::Rect(l, t, rr - l, b - t) : cv::Rect();
}

// The first and last pixel of each row of `mask` (CV_8U) within `box`: a convex region's outline.
std::vector<cv::Point> rowEnds(const cv::Mat& mask, const cv::Rect& box) {
  std::vector<cv::Point> ends;
  for (int v = box.y; v < box.y + box.height; ++v) {
    const auto* row = mask.ptr<uchar>(v);
    int first = box.x, last = box.x + box.width - 1;
    while (first <= last && !row[first]) ++first;
    while (last >= first && !row[last]) --last;
    if (first > last) continue;
    ends.emplace_back(first, v);
    ends.emplace_back(last, v);
  }
  return ends;
}

}  // namespace

cv::Mat sphereSilhouette(cv::Size size, const cv::Matx33d& K, const Eigen::Vector3d& c,
                         double radius) {
  cv::Mat out = cv::Mat::zeros(size, CV_8U);
  drawSilhouettes({&out}, {radius}, K, c);
  return out;
}

HandMasker::HandMasker(HandMaskConfig config)
    : config_(config), appearance_((config.validate(), config.appearance)) {}

cv::Mat HandMasker::keepComponents(const cv::Mat& score, const cv::Mat& silhouette,
                                   const cv::Mat& search, int& keptCount) const {
  cv::Mat weak = (score > 1.0) & search;
  if (config_.openPx > 0) cv::morphologyEx(weak, weak, cv::MORPH_OPEN, disc(config_.openPx));
  if (config_.closePx > 0) cv::morphologyEx(weak, weak, cv::MORPH_CLOSE, disc(config_.closePx));
  weak &= search;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(weak, labels, stats, centroids, 8, CV_32S);
  const double silArea = std::max(1, cv::countNonZero(silhouette));
  std::vector<int> outside(std::size_t(n), 0), strong(std::size_t(n), 0);
  for (int y = 0; y < labels.rows; ++y) {
    const auto* l = labels.ptr<int>(y);
    const auto* s = score.ptr<float>(y);
    const auto* in = silhouette.ptr<uchar>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (l[x] == 0) continue;
      outside[std::size_t(l[x])] += in[x] ? 0 : 1;
      strong[std::size_t(l[x])] += s[x] > config_.strongScore ? 1 : 0;
    }
  }
  cv::Mat kept = cv::Mat::zeros(score.size(), CV_8U);
  keptCount = 0;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    const bool entering = outside[std::size_t(i)] > 0 && strong[std::size_t(i)] > 0 &&
                          area >= config_.minAreaFraction * silArea;
    const bool large = strong[std::size_t(i)] >= config_.minAreaFraction * silArea &&
                       area >= config_.minInteriorAreaFraction * silArea;
    if (!entering && !large) continue;
    ++keptCount;
    // The component with its holes filled: a hand's uniform middle may score low in places.
    cv::Mat mine = labels == i;
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mine, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(kept, contours, -1, cv::Scalar(255), cv::FILLED);
  }
  return kept;
}

HandMaskFrame HandMasker::update(const cv::Mat& image, const cv::Matx33d& K, const Pose& board,
                                 const Eigen::Vector3d& planetCentreCamera, double radius,
                                 const cv::Mat& notBoard) {
  HandMaskFrame out;
  const cv::Size size = image.size();
  out.soft = cv::Mat::zeros(size, CV_32F);
  out.silhouette = cv::Mat::zeros(size, CV_8U);
  // The planet's silhouette, the grown one searched for a hand, and the band around it.
  const double grown = radius * (1 + config_.silhouetteMargin);
  cv::Mat grownSilhouette = cv::Mat::zeros(size, CV_8U), search = cv::Mat::zeros(size, CV_8U);
  drawSilhouettes({&out.silhouette, &grownSilhouette, &search},
                  {radius, grown, grown + radius * config_.ringFraction}, K, planetCentreCamera);
  // A pose that is not one (the tracker reports none such; a caller might): nothing masked,
  // nothing learned.
  if (!board.finite() || !planetCentreCamera.allFinite() || !(radius > 0) ||
      !std::isfinite(radius) || image.empty())
    return out;
  const cv::Rect box = cv::boundingRect(search);
  // The model's texels behind the searched box (worked on with their margin; learned there),
  // and this frame's tile of the rest of the square (learned outside the former).
  const Eigen::Vector3d foot = board.inverse().apply(planetCentreCamera);
  const cv::Matx33d imageFromTexel = appearance_.place(K, board, foot.head<2>());
  const FrameGain gain = appearance_.gain(image, imageFromTexel);
  out.gain = gain.gain;
  const cv::Rect square = appearance_.square();
  const int margin = appearance_.margin();
  cv::Rect behind, learnt;
  PlaneView view;
  ForegroundScore fg;
  if (box.area() > 0) {
    behind = appearance_.texelsSeenIn(imageFromTexel, rowEnds(search, box));
    view = appearance_.view(image, imageFromTexel, grownWithin(behind, margin, square), notBoard);
    fg = appearance_.foreground(view, gain.gain);
    learnt = shrunkWithin(view.region, margin - 1, square);
  }
  const cv::Rect tile = appearance_.nextTile();
  if ((tile & learnt) != tile) {
    const PlaneView tileView =
        appearance_.view(image, imageFromTexel, grownWithin(tile, margin, square), notBoard);
    const ForegroundScore tileFg = appearance_.foreground(tileView, gain.gain);
    appearance_.learn(tileView, tileFg, tile, learnt);
  }
  if (box.area() == 0) return out;
  appearance_.learn(view, fg, learnt);
  // The texels' scores in the searched box of the image.
  const cv::Matx33d shift(1, 0, -box.x, 0, 1, -box.y, 0, 0, 1);
  const cv::Matx33d fromView(1, 0, view.region.x, 0, 1, view.region.y, 0, 0, 1);
  cv::Mat score;
  cv::warpPerspective(fg.score, score, shift * imageFromTexel * fromView, box.size(),
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  const cv::Mat kept = keepComponents(score, grownSilhouette(box), search(box), out.components);
  cv::Mat soft;
  kept.convertTo(soft, CV_32F, 1.0 / 255);
  if (config_.featherPx > 0) cv::GaussianBlur(soft, soft, cv::Size(0, 0), config_.featherPx);
  soft.copyTo(out.soft(box));
  // The planet's silhouette lies within the searched box.
  if (cv::countNonZero(out.silhouette(box)) > 0)
    out.coverage = cv::mean(out.soft(box), out.silhouette(box))[0];
  return out;
}

}  // namespace ps::tracking
