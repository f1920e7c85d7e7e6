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

// The three channels' sum (a brightness that a shadow scales).
cv::Mat channelSum(const cv::Mat& bgr) {
  std::vector<cv::Mat> ch;
  cv::split(bgr, ch);
  return ch[0] + ch[1] + ch[2];
}

// Per-channel median of frame / model over learned texels bright enough to measure: the global
// gain and white balance between the model and this frame.
cv::Vec3d medianGain(const cv::Mat& image, const cv::Mat& model, const cv::Mat& learned,
                     int& samples) {
  std::vector<float> ratio[3];
  for (int y = 0; y < image.rows; y += 2) {
    const auto* in = image.ptr<cv::Vec3f>(y);
    const auto* m = model.ptr<cv::Vec3f>(y);
    const auto* ok = learned.ptr<uchar>(y);
    for (int x = y % 4 / 2; x < image.cols; x += 2) {
      if (!ok[x]) continue;
      if (std::min({m[x][0], m[x][1], m[x][2]}) < 20.0f) continue;
      for (int c = 0; c < 3; ++c) ratio[c].push_back(in[x][c] / m[x][c]);
    }
  }
  samples = int(ratio[0].size());
  cv::Vec3d gain(1, 1, 1);
  if (samples < 200) return gain;  // too little of the board seen: assume no change
  for (int c = 0; c < 3; ++c) {
    auto mid = ratio[c].begin() + std::ptrdiff_t(ratio[c].size() / 2);
    std::nth_element(ratio[c].begin(), mid, ratio[c].end());
    gain[c] = *mid;
  }
  return gain;
}

// Chromaticity distance to the nearest of the model's 3x3 neighbours (misregistration of one
// texel is not a change), against a threshold that grows where the light is too low for
// chromaticity to be measured through the noise. One pass, no temporaries: the hot loop.
cv::Mat chromaScore(const cv::Mat& image, const cv::Mat& sumI, const cv::Mat& model,
                    const cv::Mat& sumM, const BoardAppearanceConfig& c) {
  const int rows = image.rows, cols = image.cols;
  cv::Mat cM(rows, cols, CV_32FC3);
  for (int y = 0; y < rows; ++y) {
    const auto* m = model.ptr<cv::Vec3f>(y);
    const auto* s = sumM.ptr<float>(y);
    auto* out = cM.ptr<cv::Vec3f>(y);
    for (int x = 0; x < cols; ++x) out[x] = m[x] * (1.0f / std::max(s[x], 1.0f));
  }
  const float noise = float(4.5 * c.noiseSigma), floor = float(c.chromaThreshold);
  cv::Mat score(rows, cols, CV_32F);
  for (int y = 0; y < rows; ++y) {
    const auto* in = image.ptr<cv::Vec3f>(y);
    const auto* sI = sumI.ptr<float>(y);
    const auto* sM = sumM.ptr<float>(y);
    auto* out = score.ptr<float>(y);
    const cv::Vec3f* near[3] = {cM.ptr<cv::Vec3f>(std::max(y - 1, 0)), cM.ptr<cv::Vec3f>(y),
                                cM.ptr<cv::Vec3f>(std::min(y + 1, rows - 1))};
    for (int x = 0; x < cols; ++x) {
      const cv::Vec3f ci = in[x] * (1.0f / std::max(sI[x], 1.0f));
      float best = 1e9f;
      for (const cv::Vec3f* r : near)
        for (int dx = -1; dx <= 1; ++dx) {
          const cv::Vec3f& cm = r[std::clamp(x + dx, 0, cols - 1)];
          const float d0 = ci[0] - cm[0], d1 = ci[1] - cm[1], d2 = ci[2] - cm[2];
          best = std::min(best, d0 * d0 + d1 * d1 + d2 * d2);
        }
      const float threshold = floor + noise / std::max(std::min(sI[x], sM[x]), 1.0f);
      out[x] = std::sqrt(best) / threshold;
    }
  }
  return score;
}

// Brighter than the brightest of the model's 3x3 neighbours allows, or darker than the
// deepest shadow on the darkest of them: > 1.
cv::Mat brightnessScore(const cv::Mat& sumI, const cv::Mat& sumM, const BoardAppearanceConfig& c) {
  const double noise = 3.0 * c.noiseSigma * std::sqrt(3.0);
  cv::Mat lo, hi;
  cv::erode(sumM, lo, cv::Mat());
  cv::dilate(sumM, hi, cv::Mat());
  hi = hi * c.brightRatio + noise;
  lo = lo * c.shadowRatio - noise;
  cv::Mat above, below;
  cv::divide(sumI, hi, above);
  cv::divide(lo, cv::max(sumI, 1.0), below);
  return cv::max(above, below);
}

// Where the model has texture, how much of it the frame has lost: (1 - NCC) / (1 - minNcc)
// over a window; NCC is blind to gain and to a shadow's uniform darkening.
cv::Mat textureScore(const cv::Mat& sumI, const cv::Mat& sumM, const BoardAppearanceConfig& c) {
  const cv::Size w(c.textureWindow, c.textureWindow);
  const cv::Mat I = sumI / 3.0, M = sumM / 3.0;
  cv::Mat mI, mM, mII, mMM, mIM;
  cv::boxFilter(I, mI, CV_32F, w);
  cv::boxFilter(M, mM, CV_32F, w);
  cv::boxFilter(I.mul(I), mII, CV_32F, w);
  cv::boxFilter(M.mul(M), mMM, CV_32F, w);
  cv::boxFilter(I.mul(M), mIM, CV_32F, w);
  const cv::Mat varI = cv::max(mII - mI.mul(mI), 0.0);
  const cv::Mat varM = cv::max(mMM - mM.mul(mM), 0.0);
  const cv::Mat cov = mIM - mI.mul(mM);
  cv::Mat denom;
  cv::sqrt(varI.mul(varM) + 1e-3, denom);
  cv::Mat ncc;
  cv::divide(cov, denom, ncc);
  cv::Mat score = (1.0 - ncc) / (1.0 - c.textureMinNcc);
  score.setTo(0, varM < c.textureMinStd * c.textureMinStd);
  return score;
}

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
}

int BoardAppearance::learnedTexels() const {
  return cv::countNonZero(count_);
}

PlaneView BoardAppearance::view(const cv::Mat& image, const cv::Matx33d& K, const Pose& board,
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
  PlaneView v;
  v.imageFromTexel = K * plane * boardFromTexel;
  cv::Mat bgr;
  if (image.channels() == 1)
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  else
    bgr = image;
  const cv::Size size(side_, side_);
  cv::Mat warped;
  cv::warpPerspective(bgr, warped, v.imageFromTexel, size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT);
  warped.convertTo(v.image, CV_32FC3);
  // In the image (a texel's whole bilinear footprint) and in front of the camera.
  cv::Mat inside(image.size(), CV_8U, cv::Scalar(255));
  cv::warpPerspective(inside, v.valid, v.imageFromTexel, size,
                      cv::INTER_NEAREST | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT);
  cv::erode(v.valid, v.valid, cv::Mat(), {-1, -1}, 2);
  const cv::Matx33d& H = v.imageFromTexel;
  for (int j = 0; j < side_; ++j) {
    auto* ok = v.valid.ptr<uchar>(j);
    for (int i = 0; i < side_; ++i)
      if (H(2, 0) * i + H(2, 1) * j + H(2, 2) < 0.02) ok[i] = 0;  // camera z (m)
  }
  return v;
}

ForegroundScore BoardAppearance::foreground(const PlaneView& v) const {
  ForegroundScore out;
  const cv::Mat learned = (count_ > 0) & v.valid;
  out.gain = medianGain(v.image, mean_, learned, out.gainSamples);
  cv::Mat model;
  cv::multiply(mean_, cv::Scalar(out.gain[0], out.gain[1], out.gain[2]), model);
  const cv::Mat sumI = channelSum(v.image), sumM = channelSum(model);
  cv::Mat score = cv::max(chromaScore(v.image, sumI, model, sumM, config_),
                          brightnessScore(sumI, sumM, config_));
  score = cv::max(score, textureScore(sumI, sumM, config_));
  score.setTo(0, ~learned);
  out.score = score;
  const double tol = config_.learnBrightnessTolerance;
  cv::Mat ratio;
  cv::divide(sumI, cv::max(sumM, 1.0), ratio);
  out.steady = (ratio > 1.0 / (1.0 + tol)) & (ratio < 1.0 + tol);
  return out;
}

void BoardAppearance::learn(const PlaneView& v, const ForegroundScore& fg) {
  cv::Mat busy = fg.score > config_.learnBelow;
  if (config_.learnGuardTexels > 0) {
    const int k = 2 * config_.learnGuardTexels + 1;
    cv::dilate(busy, busy, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  const float rate = float(config_.learnRate);
  const float warm = float(config_.warmupFrames);
  const float forget = float(config_.forgetAfterFrames);
  for (int j = 0; j < side_; ++j) {
    const auto* ok = v.valid.ptr<uchar>(j);
    const auto* no = busy.ptr<uchar>(j);
    const auto* steady = fg.steady.ptr<uchar>(j);
    const auto* in = v.image.ptr<cv::Vec3f>(j);
    auto* m = mean_.ptr<cv::Vec3f>(j);
    auto* n = count_.ptr<float>(j);
    auto* kept = kept_.ptr<float>(j);
    for (int i = 0; i < side_; ++i) {
      if (!ok[i]) continue;
      if (n[i] > 0 && (no[i] || !steady[i])) {
        if (++kept[i] < forget) continue;
        n[i] = 0;  // kept out too long: start again from this frame
      }
      kept[i] = 0;
      const float a = n[i] < warm ? 1.0f / (n[i] + 1.0f) : rate;
      m[i] += a * (in[i] - m[i]);
      n[i] = std::min(n[i] + 1.0f, 1e6f);
    }
  }
}

}  // namespace ps::tracking
