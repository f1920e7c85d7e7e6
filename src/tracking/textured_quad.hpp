#pragma once
// Anti-aliased drawing of planar textures under a homography, for synthetic video and tests.
#include <opencv2/core.hpp>

namespace ps::tracking {

// Draws `texture` (8-bit, 1 or 3 channels like `image`; texel (i, j) covers [j, j+1] x [i, i+1]
// in continuous texture coordinates) into `image` where the homography `H` maps continuous
// texture coordinates to image pixels (OpenCV convention: pixel centres at integers). Edges
// are anti-aliased by rendering the covered box at `supersample` x `supersample` samples per
// pixel (nearest texel per sample) and box filtering; the result is blended by coverage.
// Nothing is drawn where the quad is behind the camera (H's third row <= 0 at a corner).
void drawTexturedQuad(cv::Mat& image, const cv::Mat& texture, const cv::Matx33d& H,
                      int supersample = 8);

// The same with several homographies averaged (motion blur within one exposure). `shortcut`
// off samples every pixel's every sample (the reference the shortcut is tested against); on,
// a pixel whose samples provably all fall in one texel, or all outside, is not sampled one by one.
void drawTexturedQuadBlurred(cv::Mat& image, const cv::Mat& texture,
                             const std::vector<cv::Matx33d>& Hs, int supersample = 8,
                             bool shortcut = true);

}  // namespace ps::tracking
