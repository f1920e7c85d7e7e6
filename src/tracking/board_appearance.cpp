#include "tracking/board_appearance.hpp"

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
    throw core::InputError("board appearance: " + field + " " + rule + " (got " +
                           core::exactNumber(value) + ")");
}

// The image at the pixel nearest (u, v), as b, g, r: `image` 8-bit BGR or grey, (u, v) inside.
cv::Vec3f nearestPixel(const cv::Mat& image, double u, double v) {
  const int n = image.channels();
  const uchar* p = image.ptr<uchar>(int(v + 0.5)) + int(u + 0.5) * n;
  return n == 1 ? cv::Vec3f(p[0], p[0], p[0]) : cv::Vec3f(p[0], p[1], p[2]);
}

// Per-channel median of frame / model over learned texels bright enough to measure (every 4th
// texel of every 4th row, staggered, over the whole square: 1 in 16): the global gain and white
// balance between the model and this frame.
FrameGain medianGain(const cv::Mat& image, const cv::Matx33d& H, const cv::Mat& model,
                     const cv::Mat& count) {
  std::vector<float> ratio[3];
  for (auto& r : ratio)
    r.reserve(std::size_t(model.rows / 4 + 1) * std::size_t(model.cols / 4 + 1));
  const double maxU = image.cols - 3, maxV = image.rows - 3;  // a texel's footprint inside
  for (int y = 0; y < model.rows; y += 4) {
    const auto* m = model.ptr<cv::Vec3f>(y);
    const auto* n = count.ptr<float>(y);
    for (int x = y % 8 / 2; x < model.cols; x += 4) {
      if (n[x] <= 0 || std::min({m[x][0], m[x][1], m[x][2]}) < 20.0f) continue;
      const double w = H(2, 0) * x + H(2, 1) * y + H(2, 2);
      if (w < 0.02) continue;  // camera z (m)
      const double u = (H(0, 0) * x + H(0, 1) * y + H(0, 2)) / w;
      const double v = (H(1, 0) * x + H(1, 1) * y + H(1, 2)) / w;
      if (!(u >= 2 && u <= maxU && v >= 2 && v <= maxV)) continue;
      const cv::Vec3f in = nearestPixel(image, u, v);
      for (int c = 0; c < 3; ++c) ratio[c].push_back(in[c] / m[x][c]);
    }
  }
  FrameGain out;
  out.samples = int(ratio[0].size());
  if (out.samples < 200) return out;  // too little of the board seen: assume no change
  for (int c = 0; c < 3; ++c) {
    auto mid = ratio[c].begin() + std::ptrdiff_t(ratio[c].size() / 2);
    std::nth_element(ratio[c].begin(), mid, ratio[c].end());
    out.gain[c] = *mid;
  }
  return out;
}

// What the scores read of a texel's neighbourhood, made in one pass over the region: the
// frame's and the model's brightness (the three channels' sum, which a shadow scales), the
// model's chromaticity, and the 7x7 window means of the grey levels, their squares and their
// product (for the texture test's NCC).
struct TexelSums {
  cv::Mat sumI, sumM;   // CV_32F
  cv::Mat lowM, highM;  // CV_32F, the model's darkest and brightest of the 3x3 neighbours
  cv::Mat chromaM;      // CV_32FC3, the model's b, g, r over their sum
  cv::Mat moments;      // CV_32FC4, window means of I, M, I², M² (I, M: grey levels)
  cv::Mat cross;        // CV_32F, window mean of I·M
};

TexelSums texelSums(const cv::Mat& image, const cv::Mat& mean, const cv::Vec3f& gain, int window) {
  const int rows = image.rows, cols = image.cols;
  TexelSums t{cv::Mat(rows, cols, CV_32F),
              cv::Mat(rows, cols, CV_32F),
              cv::Mat(),
              cv::Mat(),
              cv::Mat(rows, cols, CV_32FC3),
              cv::Mat(rows, cols, CV_32FC4),
              cv::Mat(rows, cols, CV_32F)};
  for (int y = 0; y < rows; ++y) {
    const auto* in = image.ptr<cv::Vec3f>(y);
    const auto* m = mean.ptr<cv::Vec3f>(y);
    auto* sI = t.sumI.ptr<float>(y);
    auto* sM = t.sumM.ptr<float>(y);
    auto* cM = t.chromaM.ptr<cv::Vec3f>(y);
    auto* mo = t.moments.ptr<cv::Vec4f>(y);
    auto* cr = t.cross.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      const cv::Vec3f model = m[x].mul(gain);
      sI[x] = in[x][0] + in[x][1] + in[x][2];
      sM[x] = model[0] + model[1] + model[2];
      cM[x] = model * (1.0f / std::max(sM[x], 1.0f));
      const float I = sI[x] / 3.0f, M = sM[x] / 3.0f;
      mo[x] = cv::Vec4f(I, M, I * I, M * M);
      cr[x] = I * M;
    }
  }
  cv::erode(t.sumM, t.lowM, cv::Mat());
  cv::dilate(t.sumM, t.highM, cv::Mat());
  const cv::Size w(window, window);
  cv::boxFilter(t.moments, t.moments, CV_32F, w);
  cv::boxFilter(t.cross, t.cross, CV_32F, w);
  return t;
}

// One texel's score against the model's 3x3 neighbours (misregistration of one texel is not a
// change): the largest of
//  (a) the chromaticity distance to the nearest neighbour, against a threshold that grows where
//      the light is too low for chromaticity to be measured through the noise;
//  (b) brighter than the brightest neighbour allows, or darker than the deepest shadow on the
//      darkest: > 1;
//  (c) where the model has texture, how much of it the frame has lost: (1 - NCC) / (1 - minNcc)
//      over the window; NCC is blind to gain and to a shadow's uniform darkening.
struct TexelScorer {
  const BoardAppearanceConfig& c;
  float chromaNoise = float(4.5 * c.noiseSigma), chromaFloor = float(c.chromaThreshold);
  float brightNoise = float(3.0 * c.noiseSigma * std::sqrt(3.0));
  float bright = float(c.brightRatio), shadow = float(c.shadowRatio);
  float minVar = float(c.textureMinStd * c.textureMinStd);
  float nccScale = float(1.0 / (1.0 - c.textureMinNcc));

  float operator()(const TexelSums& t, const cv::Vec3f& in, int y, int x) const {
    const float sI = t.sumI.at<float>(y, x), sM = t.sumM.at<float>(y, x);
    float score = 0;
    const float top = t.highM.at<float>(y, x) * bright + brightNoise;
    if (top > 0) score = sI / top;
    score = std::max(score, (t.lowM.at<float>(y, x) * shadow - brightNoise) / std::max(sI, 1.0f));
    const cv::Vec4f& mo = t.moments.at<cv::Vec4f>(y, x);
    const float varM = std::max(mo[3] - mo[1] * mo[1], 0.0f);
    if (!(varM < minVar)) {
      const float varI = std::max(mo[2] - mo[0] * mo[0], 0.0f);
      const float cov = t.cross.at<float>(y, x) - mo[0] * mo[1];
      const float ncc = cov / std::sqrt(varI * varM + 1e-3f);
      score = std::max(score, (1.0f - ncc) * nccScale);
    }
    // The chromaticity distance to the nearest neighbour, the texel's own first: once a distance
    // puts (a) at or below the other tests' score, the nearest cannot raise the maximum.
    const float threshold = chromaFloor + chromaNoise / std::max(std::min(sI, sM), 1.0f);
    const float enough = score * threshold * score * threshold;
    const cv::Vec3f ci = in * (1.0f / std::max(sI, 1.0f));
    const auto distance = [&ci](const cv::Vec3f& cm) {
      const float d0 = ci[0] - cm[0], d1 = ci[1] - cm[1], d2 = ci[2] - cm[2];
      return d0 * d0 + d1 * d1 + d2 * d2;
    };
    float best = distance(t.chromaM.at<cv::Vec3f>(y, x));
    const int rows = t.sumI.rows, cols = t.sumI.cols;
    for (int dy = -1; dy <= 1 && best > enough; ++dy) {
      const auto* cM = t.chromaM.ptr<cv::Vec3f>(std::clamp(y + dy, 0, rows - 1));
      for (int dx = -1; dx <= 1 && best > enough; ++dx)
        best = std::min(best, distance(cM[std::clamp(x + dx, 0, cols - 1)]));
    }
    return std::max(score, std::sqrt(best) / threshold);
  }
};

}  // namespace

void BoardAppearanceConfig::validate() const {
  require(std::isfinite(halfSizeM) && halfSizeM > 0, "half_size_m", "is not > 0", halfSizeM);
  require(std::isfinite(texelM) && texelM > 0, "texel_m", "is not > 0", texelM);
  require(halfSizeM / texelM <= 2000, "texel_m", "makes more than 4000 texels a side", texelM);
  require(halfSizeM / texelM >= 8, "texel_m", "makes fewer than 16 texels a side", texelM);
  require(learnRate > 0 && learnRate <= 1, "learn_rate", "is not in (0, 1]", learnRate);
  require(warmupFrames >= 1, "warmup_frames", "is not >= 1", warmupFrames);
  require(std::isfinite(noiseSigma) && noiseSigma >= 0, "noise_sigma", "is not >= 0", noiseSigma);
  require(std::isfinite(chromaThreshold) && chromaThreshold > 0, "chroma_threshold", "is not > 0",
          chromaThreshold);
  require(shadowRatio >= 0 && shadowRatio < 1, "shadow_ratio", "is not in [0, 1)", shadowRatio);
  require(std::isfinite(brightRatio) && brightRatio > 1, "bright_ratio", "is not > 1", brightRatio);
  require(std::isfinite(textureMinStd) && textureMinStd >= 0, "texture_min_std", "is not >= 0",
          textureMinStd);
  require(textureMinNcc >= -1 && textureMinNcc < 1, "texture_min_ncc", "is not in [-1, 1)",
          textureMinNcc);
  require(textureWindow >= 3 && textureWindow % 2 == 1 && textureWindow <= 31, "texture_window",
          "is not an odd number in 3..31", textureWindow);
  require(std::isfinite(learnBelow) && learnBelow > 0, "learn_below", "is not > 0", learnBelow);
  require(learnGuardTexels >= 0 && learnGuardTexels <= 50, "learn_guard_texels", "is not in 0..50",
          learnGuardTexels);
  require(std::isfinite(learnBrightnessTolerance) && learnBrightnessTolerance > 0,
          "learn_brightness_tolerance", "is not > 0", learnBrightnessTolerance);
  require(forgetAfterFrames >= 1, "forget_after_frames", "is not >= 1", forgetAfterFrames);
  require(learnTiles >= 1 && learnTiles <= 64, "learn_tiles", "is not in 1..64", learnTiles);
}

BoardAppearance::BoardAppearance(BoardAppearanceConfig config) : config_(config) {
  config_.validate();
  side_ = 2 * int(std::ceil(config_.halfSizeM / config_.texelM)) + 1;
  reset();
}

void BoardAppearance::reset() {
  mean_ = cv::Mat::zeros(side_, side_, CV_32FC3);
  count_ = cv::Mat::zeros(side_, side_, CV_32F);
  kept_ = cv::Mat::zeros(side_, side_, CV_32F);
  centred_ = false;
  tile_ = 0;
}

int BoardAppearance::learnedTexels() const {
  return cv::countNonZero(count_);
}

int BoardAppearance::margin() const {
  // A score reads the window of the texture test (and the 3x3 of the others); a texel's
  // validity the 2-texel erosion; learning the guard's dilation of the scores; one more for the
  // bilinear reading of the region's edge.
  return config_.textureWindow / 2 + 2 + config_.learnGuardTexels + 1;
}

cv::Matx33d BoardAppearance::place(const cv::Matx33d& K, const Pose& board,
                                   const Eigen::Vector2d& centreOnBoard) {
  if (centred_ && (centreOnBoard - centre_).norm() > 0.25 * config_.halfSizeM) reset();
  if (!centred_) {
    centre_ = centreOnBoard;
    centred_ = true;
  }
  // Texel (column i, row j) -> board (x, y): rows run toward -y, as a printed sheet's image.
  const double s = config_.texelM, half = 0.5 * (side_ - 1);
  const cv::Matx33d boardFromTexel(s, 0, centre_.x() - half * s, 0, -s, centre_.y() + half * s, 0,
                                   0, 1);
  cv::Matx33d plane;
  for (int r = 0; r < 3; ++r) {
    plane(r, 0) = board.R(r, 0);
    plane(r, 1) = board.R(r, 1);
    plane(r, 2) = board.t(r);
  }
  return K * plane * boardFromTexel;
}

cv::Rect BoardAppearance::texelsSeenIn(const cv::Matx33d& imageFromTexel,
                                       const std::vector<cv::Point>& outline) const {
  const cv::Matx33d texelFromImage = imageFromTexel.inv();
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  // A homography maps a convex region onto a convex one bounded by its outline's images, when
  // every outline point's ray meets the plane ahead of the camera (w > 0: 1 / camera z).
  for (const cv::Point& q : outline) {
    const cv::Vec3d p = texelFromImage * cv::Vec3d(q.x, q.y, 1);
    if (!(p[2] > 1e-9)) return square();
    x0 = std::min(x0, p[0] / p[2]), x1 = std::max(x1, p[0] / p[2]);
    y0 = std::min(y0, p[1] / p[2]), y1 = std::max(y1, p[1] / p[2]);
  }
  if (outline.empty()) return {};
  const auto clampTo = [this](double v) { return int(std::clamp(v, 0.0, double(side_))); };
  const int l = clampTo(std::floor(x0) - 1), r = clampTo(std::ceil(x1) + 2);
  const int t = clampTo(std::floor(y0) - 1), b = clampTo(std::ceil(y1) + 2);
  return cv::Rect(l, t, r - l, b - t);
}

FrameGain BoardAppearance::gain(const cv::Mat& image, const cv::Matx33d& imageFromTexel) const {
  return medianGain(image, imageFromTexel, mean_, count_);
}

cv::Rect BoardAppearance::nextTile() {
  const int n = config_.learnTiles, i = tile_ % n, j = tile_ / n;
  tile_ = (tile_ + 1) % (n * n);
  const auto edge = [this, n](int k) { return k * side_ / n; };
  return cv::Rect(edge(i), edge(j), edge(i + 1) - edge(i), edge(j + 1) - edge(j));
}

PlaneView BoardAppearance::view(const cv::Mat& image, const cv::Matx33d& imageFromTexel,
                                cv::Rect region, const cv::Mat& notBoard) {
  PlaneView v;
  v.region = region & square();
  v.imageFromTexel = imageFromTexel;
  const cv::Size size = v.region.size();
  if (size.area() == 0) return v;
  // The region's (column, row) -> the square's texel -> the image.
  const cv::Matx33d H = imageFromTexel * cv::Matx33d(1, 0, v.region.x, 0, 1, v.region.y, 0, 0, 1);
  cv::Mat warped;
  cv::warpPerspective(image, warped, H, size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT);
  if (warped.channels() == 1) cv::cvtColor(warped, warped, cv::COLOR_GRAY2BGR);
  warped.convertTo(v.image, CV_32FC3);
  // In the image (a texel's whole bilinear footprint) and in front of the camera.
  if (inside_.size() != image.size()) inside_ = cv::Mat(image.size(), CV_8U, cv::Scalar(255));
  cv::warpPerspective(inside_, v.valid, H, size, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT);
  cv::erode(v.valid, v.valid, cv::Mat(), {-1, -1}, 2);
  for (int j = 0; j < size.height; ++j) {
    auto* ok = v.valid.ptr<uchar>(j);
    for (int i = 0; i < size.width; ++i)
      if (H(2, 0) * i + H(2, 1) * j + H(2, 2) < 0.02) ok[i] = 0;  // camera z (m)
  }
  if (!notBoard.empty() && notBoard.size() == image.size() && cv::countNonZero(notBoard) > 0) {
    // Grown by the bilinear footprint's texel, as `valid` is shrunk.
    cv::warpPerspective(notBoard, v.notBoard, H, size, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                        cv::BORDER_CONSTANT);
    cv::dilate(v.notBoard, v.notBoard, cv::Mat(), {-1, -1}, 1);
  }
  return v;
}

ForegroundScore BoardAppearance::foreground(const PlaneView& v, const cv::Vec3d& gain) const {
  ForegroundScore out;
  if (v.region.area() == 0) return out;
  const TexelSums sums =
      texelSums(v.image, mean_(v.region), cv::Vec3f(gain), config_.textureWindow);
  const TexelScorer scorer{config_};
  const float tol = float(config_.learnBrightnessTolerance);
  const float steadyLo = 1.0f / (1.0f + tol), steadyHi = 1.0f + tol;
  out.score.create(v.region.size(), CV_32F);
  out.steady.create(v.region.size(), CV_8U);
  for (int y = 0; y < v.region.height; ++y) {
    const auto* in = v.image.ptr<cv::Vec3f>(y);
    const auto* n = count_.ptr<float>(v.region.y + y) + v.region.x;
    const auto* ok = v.valid.ptr<uchar>(y);
    const auto* sI = sums.sumI.ptr<float>(y);
    const auto* sM = sums.sumM.ptr<float>(y);
    auto* score = out.score.ptr<float>(y);
    auto* steady = out.steady.ptr<uchar>(y);
    for (int x = 0; x < v.region.width; ++x) {
      score[x] = n[x] > 0 && ok[x] ? scorer(sums, in[x], y, x) : 0.0f;  // unlearned: 0
      const float ratio = sI[x] / std::max(sM[x], 1.0f);
      steady[x] = ratio > steadyLo && ratio < steadyHi ? 255 : 0;
    }
  }
  return out;
}

void BoardAppearance::learn(const PlaneView& v, const ForegroundScore& fg, const cv::Rect& where,
                            const cv::Rect& skip) {
  const cv::Rect area = where & v.region;
  if (area.area() == 0) return;
  cv::Mat busy = fg.score > config_.learnBelow;
  if (config_.learnGuardTexels > 0) {
    const int k = 2 * config_.learnGuardTexels + 1;
    cv::dilate(busy, busy, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  const float rate = float(config_.learnRate);
  const float warm = float(config_.warmupFrames);
  const float forget = float(config_.forgetAfterFrames);
  const cv::Point o = v.region.tl();  // the view's texel (0, 0) in the square
  for (int j = area.y; j < area.y + area.height; ++j) {
    const auto* ok = v.valid.ptr<uchar>(j - o.y);
    const auto* no = busy.ptr<uchar>(j - o.y);
    const auto* steady = fg.steady.ptr<uchar>(j - o.y);
    const auto* in = v.image.ptr<cv::Vec3f>(j - o.y);
    const auto* other = v.notBoard.empty() ? nullptr : v.notBoard.ptr<uchar>(j - o.y);
    auto* m = mean_.ptr<cv::Vec3f>(j);
    auto* n = count_.ptr<float>(j);
    auto* kept = kept_.ptr<float>(j);
    const bool skipRow = j >= skip.y && j < skip.y + skip.height;
    for (int i = area.x; i < area.x + area.width; ++i) {
      const int k = i - o.x;  // in the view
      if (!ok[k] || (other && other[k])) continue;
      if (skipRow && i >= skip.x && i < skip.x + skip.width) continue;
      if (n[i] > 0 && (no[k] || !steady[k])) {
        if (++kept[i] < forget) continue;
        n[i] = 0;  // kept out too long: start again from this frame
      }
      kept[i] = 0;
      const float a = n[i] < warm ? 1.0f / (n[i] + 1.0f) : rate;
      m[i] += a * (in[k] - m[i]);
      n[i] = std::min(n[i] + 1.0f, 1e6f);
    }
  }
}

}  // namespace ps::tracking
