#include "tracking/hand_mask.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/input_error.hpp"

namespace ps::tracking {

namespace {

void require(bool ok, const std::string& field, const std::string& rule, double value) {
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
  require(std::isfinite(silhouetteMargin) && silhouetteMargin >= 0 && silhouetteMargin <= 1,
          "silhouette_margin", "is not in [0, 1]", silhouetteMargin);
  require(std::isfinite(ringFraction) && ringFraction > 0 && ringFraction <= 2, "ring_fraction",
          "is not in (0, 2]", ringFraction);
  require(std::isfinite(strongScore) && strongScore >= 1, "strong_score", "is not >= 1",
          strongScore);
  require(minAreaFraction >= 0 && minAreaFraction < 1, "min_area_fraction", "is not in [0, 1)",
          minAreaFraction);
  require(minInteriorAreaFraction >= 0 && minInteriorAreaFraction < 1, "min_interior_area_fraction",
          "is not in [0, 1)", minInteriorAreaFraction);
  require(openPx >= 0 && openPx <= 20, "open_px", "is not in 0..20", openPx);
  require(closePx >= 0 && closePx <= 20, "close_px", "is not in 0..20", closePx);
  require(std::isfinite(featherPx) && featherPx >= 0 && featherPx <= 50, "feather_px",
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

cv::Mat sphereSilhouette(cv::Size size, const cv::Matx33d& K, const Eigen::Vector3d& c,
                         double radius) {
  cv::Mat out = cv::Mat::zeros(size, CV_8U);
  const double cc = c.squaredNorm(), r2 = radius * radius;
  if (!(c.z() > 0) || !(radius > 0) || !std::isfinite(cc)) return out;
  const cv::Rect box = silhouetteBounds(size, K, c, radius);
  const double fx = K(0, 0), fy = K(1, 1), cx = K(0, 2), cy = K(1, 2);
  for (int v = box.y; v < box.y + box.height; ++v) {
    auto* row = out.ptr<uchar>(v);
    const double dy = (v - cy) / fy;
    for (int u = box.x; u < box.x + box.width; ++u) {
      const double dx = (u - cx) / fx;
      // The ray t·d meets the sphere when (d·c)² >= |d|²(|c|² - r²), ahead of the camera.
      const double dc = dx * c.x() + dy * c.y() + c.z();
      const double dd = dx * dx + dy * dy + 1.0;
      if (dc > 0 && dc * dc >= dd * (cc - r2)) row[u] = 255;
    }
  }
  return out;
}

HandMasker::HandMasker(HandMaskConfig config)
    : config_(config), appearance_((config.validate(), config.appearance)) {}

cv::Mat HandMasker::keepComponents(const cv::Mat& score, const cv::Mat& silhouette,
                                   const cv::Mat& search) const {
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
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    const bool entering = outside[std::size_t(i)] > 0 && strong[std::size_t(i)] > 0 &&
                          area >= config_.minAreaFraction * silArea;
    const bool large = strong[std::size_t(i)] >= config_.minAreaFraction * silArea &&
                       area >= config_.minInteriorAreaFraction * silArea;
    if (!entering && !large) continue;
    // The component with its holes filled: a hand's uniform middle may score low in places.
    cv::Mat mine = labels == i;
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mine, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(kept, contours, -1, cv::Scalar(255), cv::FILLED);
  }
  return kept;
}

HandMaskFrame HandMasker::update(const cv::Mat& image, const cv::Matx33d& K, const Pose& board,
                                 const Eigen::Vector3d& planetCentreCamera, double radius) {
  HandMaskFrame out;
  const cv::Size size = image.size();
  out.soft = cv::Mat::zeros(size, CV_32F);
  out.silhouette = sphereSilhouette(size, K, planetCentreCamera, radius);
  // A pose that is not one (the tracker reports none such; a caller might): nothing masked,
  // nothing learned.
  if (!board.finite() || !planetCentreCamera.allFinite() || !(radius > 0) ||
      !std::isfinite(radius) || image.empty())
    return out;
  const Eigen::Vector3d foot = board.inverse().apply(planetCentreCamera);
  const PlaneView view = appearance_.view(image, K, board, foot.head<2>());
  const ForegroundScore fg = appearance_.foreground(view);
  out.gain = fg.gain;
  appearance_.learn(view, fg);
  const double grown = radius * (1 + config_.silhouetteMargin);
  const cv::Mat search =
      sphereSilhouette(size, K, planetCentreCamera, grown + radius * config_.ringFraction);
  const cv::Rect box = cv::boundingRect(search);
  if (box.area() == 0) return out;
  // The texels' scores in the searched box of the image.
  const cv::Matx33d shift(1, 0, -box.x, 0, 1, -box.y, 0, 0, 1);
  cv::Mat score;
  cv::warpPerspective(fg.score, score, shift * view.imageFromTexel, box.size(), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT);
  const cv::Mat grownSilhouette = sphereSilhouette(size, K, planetCentreCamera, grown)(box);
  const cv::Mat kept = keepComponents(score, grownSilhouette, search(box));
  cv::Mat soft;
  kept.convertTo(soft, CV_32F, 1.0 / 255);
  if (config_.featherPx > 0) cv::GaussianBlur(soft, soft, cv::Size(0, 0), config_.featherPx);
  soft.copyTo(out.soft(box));
  out.coverage = cv::mean(out.soft, out.silhouette)[0];
  if (cv::countNonZero(out.silhouette) == 0) out.coverage = 0;
  cv::Mat labels;
  out.components = cv::connectedComponents(kept, labels, 8) - 1;
  return out;
}

}  // namespace ps::tracking
