// The synthetic video's planar textures (tracking/textured_quad): the shortcut that skips the
// pixels whose samples all fall in one texel draws what sampling every sample draws, and a
// quad's anti-aliased edge covers each pixel by the area it covers.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "tracking/textured_quad.hpp"

using namespace ps;

namespace {

cv::Mat randomImage(cv::Size size, int type) {  // OpenCV's generator, seeded by the test
  cv::Mat m(size, type);
  cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(256));
  return m;
}

}  // namespace

// Random textures (1 to 12 texels a side, grey or colour) under random homographies (steep
// perspective included, some with corners off the image, some with motion blur of up to four
// homographies) at 1, 2, 3, 4 and 8 samples a side: with the shortcut and without, the same bytes.
TEST(TrackingTexturedQuad, ShortcutDrawsWhatEverySampleDraws) {
  std::mt19937 rng(20261207);
  cv::setRNGSeed(7);
  std::uniform_real_distribution<double> unit(0, 1);
  int drawn = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const bool colour = trial % 3 == 0, greyTexture = !colour || trial % 2 == 0;
    const cv::Size imageSize(72, 56);
    const cv::Mat background = randomImage(imageSize, colour ? CV_8UC3 : CV_8U);
    const cv::Size texSize(1 + int(unit(rng) * 12), 1 + int(unit(rng) * 12));
    const cv::Mat texture = randomImage(texSize, greyTexture ? CV_8U : CV_8UC3);
    // A quadrilateral about the image's middle, sometimes reaching past its edges.
    const double cx = 36 + 20 * (unit(rng) - 0.5), cy = 28 + 16 * (unit(rng) - 0.5);
    const double r = 6 + 30 * unit(rng), turn = 6.3 * unit(rng);
    std::vector<cv::Point2f> dst;
    for (int k = 0; k < 4; ++k) {
      const double a = turn + k * 1.5708 + 0.4 * (unit(rng) - 0.5);
      const double rk = r * (0.5 + unit(rng));
      dst.emplace_back(float(cx + rk * std::cos(a)), float(cy + rk * std::sin(a)));
    }
    const float W = float(texSize.width), H = float(texSize.height);
    const std::vector<cv::Point2f> src = {{0, 0}, {W, 0}, {W, H}, {0, H}};
    const cv::Matx33d H0 = cv::getPerspectiveTransform(src, dst);
    std::vector<cv::Matx33d> hs{H0};
    const int blur = int(unit(rng) * 4);
    for (int b = 0; b < blur; ++b)
      hs.push_back(cv::Matx33d(1, 0, 0.7 * (b + 1), 0, 1, 0.3 * (b + 1), 0, 0, 1) * H0);
    const int s = std::vector<int>{1, 2, 3, 4, 8}[std::size_t(trial % 5)];
    cv::Mat fast = background.clone(), every = background.clone();
    tracking::drawTexturedQuadBlurred(fast, texture, hs, s, true);
    tracking::drawTexturedQuadBlurred(every, texture, hs, s, false);
    ASSERT_EQ(cv::norm(fast, every, cv::NORM_INF), 0)
        << "trial " << trial << ", " << texSize << " texels, supersample " << s;
    if (cv::norm(fast, background, cv::NORM_INF) > 0) ++drawn;
  }
  EXPECT_GT(drawn, 250);  // the quads were drawn, not clipped away
}

// An axis-aligned quad whose edges lie on eighths of a pixel, between the 8 x 8 samples: each
// pixel is covered by exactly the fraction of its area the quad covers, so it reads the
// texture's grey times that fraction (rounded), and the background untouched elsewhere.
TEST(TrackingTexturedQuad, EdgePixelsAreCoveredByTheQuadsArea) {
  const double x0 = 10.125 - 0.5, x1 = 30.625 - 0.5, y0 = 5.375 - 0.5, y1 = 17.875 - 0.5;
  const cv::Mat texture(2, 2, CV_8U, cv::Scalar(200));
  // Texture [0, 2] x [0, 2] onto [x0, x1] x [y0, y1] (pixel x covers [x - 0.5, x + 0.5]).
  const cv::Matx33d H((x1 - x0) / 2, 0, x0, 0, (y1 - y0) / 2, y0, 0, 0, 1);
  cv::Mat image(24, 40, CV_8U, cv::Scalar(0));
  tracking::drawTexturedQuad(image, texture, H, 8);
  auto overlap = [](double a0, double a1, double b0, double b1) {
    return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
  };
  int partial = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const double cover = overlap(x - 0.5, x + 0.5, x0, x1) * overlap(y - 0.5, y + 0.5, y0, y1);
      if (cover > 0 && cover < 1) ++partial;
      EXPECT_EQ(int(image.at<std::uint8_t>(y, x)), int(std::lrint(200 * cover)))
          << "pixel " << x << ", " << y << " covered " << cover;
    }
  EXPECT_GT(partial, 60);  // the edges' pixels were checked, not only the inside
}
