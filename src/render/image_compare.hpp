#pragma once
// How close a rendered image is to a reference of the same view (render benchmarks and tests):
// the structural similarity (SSIM, Wang et al. 2004: 11x11 Gaussian windows, sigma 1.5, on
// luma; OpenCV contrib's cv::quality::QualitySSIM) and the mean absolute colour difference, both
// over the pixels a mask selects (the planet's, where either image drew it).
#include <opencv2/core.hpp>

namespace ps::render {

struct ImageDifference {
  double ssim = 0;         // mean over the mask, 1 = identical structure
  double meanAbsDiff = 0;  // mean over the mask and the three channels, grey levels
  std::size_t pixels = 0;  // pixels in the mask
};

// `image` and `reference`: 8-bit BGR of one size; `mask`: 8-bit, non-zero where compared (empty:
// every pixel). Throws std::invalid_argument for images of different sizes or types.
ImageDifference compareImages(const cv::Mat& image, const cv::Mat& reference,
                              const cv::Mat& mask = {});

// Pixels that differ from `background` (a flat colour) in either image: where the planet was drawn.
cv::Mat drawnMask(const cv::Mat& a, const cv::Mat& b, const cv::Vec3b& background);

}  // namespace ps::render
