#include "tracking/textured_quad.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace ps::tracking {

namespace {

constexpr int kMaxChannels = 4;

// Image box covered by the quad, clipped to the image; empty when not visible.
cv::Rect coveredBox(const cv::Matx33d& H, cv::Size texSize, cv::Size imageSize, bool& ok) {
  const double W = texSize.width, Ht = texSize.height;
  const cv::Vec3d corners[4] = {{0, 0, 1}, {W, 0, 1}, {W, Ht, 1}, {0, Ht, 1}};
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  ok = true;
  for (const auto& c : corners) {
    const cv::Vec3d p = H * c;
    if (!(p[2] > 1e-9)) {
      ok = false;
      return {};
    }
    x0 = std::min(x0, p[0] / p[2]);
    x1 = std::max(x1, p[0] / p[2]);
    y0 = std::min(y0, p[1] / p[2]);
    y1 = std::max(y1, p[1] / p[2]);
  }
  const int ix0 = int(std::floor(std::max(x0, -1.0))), iy0 = int(std::floor(std::max(y0, -1.0)));
  const int ix1 = int(std::ceil(std::min(x1, double(imageSize.width)))) + 1;
  const int iy1 = int(std::ceil(std::min(y1, double(imageSize.height)))) + 1;
  cv::Rect r(ix0, iy0, ix1 - ix0 + 1, iy1 - iy0 + 1);
  return r & cv::Rect(0, 0, imageSize.width, imageSize.height);
}

// One homography's samples: image point -> continuous texture coordinates, and which texel
// (texel (i, j) covers [j, j+1] x [i, i+1]) a point falls in.
struct TexelLookup {
  double m[9];  // image point -> texture coordinates (homogeneous), row by row
  int width = 0, height = 0;

  TexelLookup(const cv::Matx33d& toTexture, cv::Size size)
      : width(size.width), height(size.height) {
    for (int k = 0; k < 9; ++k) m[k] = toTexture.val[k];
  }

  // Texel column and row of image point (x, y); false outside the texture. `side` gets a
  // bit for each half-plane outside the texture the point lies in (and one for a point that
  // sees the texture's plane from behind, beyond its horizon), 0 inside.
  bool texel(double x, double y, int& col, int& row, int& side) const {
    const double w = m[6] * x + m[7] * y + m[8];
    if (!(w > 0)) {
      side = 16;
      return false;
    }
    const double iw = 1 / w;
    const double u = (m[0] * x + m[1] * y + m[2]) * iw, v = (m[3] * x + m[4] * y + m[5]) * iw;
    side = (u < 0 ? 1 : 0) | (u >= width ? 2 : 0) | (v < 0 ? 4 : 0) | (v >= height ? 8 : 0);
    // Written so that a NaN (a singular homography) is outside too, on no side.
    if (!(u >= 0 && u < width && v >= 0 && v < height)) return false;
    col = std::min(int(u), width - 1);
    row = std::min(int(v), height - 1);
    return true;
  }
};

// Accumulates one pixel's samples of one homography into `sum` (channel values) and `covered`
// (samples inside the texture). The s x s samples of pixel (x, y) lie at
// x + (i + 0.5) / s - 0.5, and likewise in y.
//
// Why not every sample every time: the cards are a texel per marker cell, so most pixels'
// samples all fall in one texel. A homography in front of the camera maps the pixel's sample
// square to a convex quadrilateral, so when its four corner samples share a texel (a convex
// cell) every sample does, and when all four lie beyond one side of the texture every sample
// does; only the pixels across a texel edge or the texture's outline are sampled one by one
// (`TrackingTexturedQuad` compares both ways on random quads).
void samplePixel(const cv::Mat& texture, const TexelLookup& look, int x, int y, int s,
                 bool shortcut, std::array<double, kMaxChannels>& sum, int& covered) {
  const int nch = texture.channels();
  const double is = 1.0 / s;
  auto at = [is](int pixel, int i) { return pixel + (i + 0.5) * is - 0.5; };  // sample i's
  auto addTexel = [&](int col, int row, int count) {
    const std::uint8_t* t = texture.ptr<std::uint8_t>(row) + std::size_t(col) * std::size_t(nch);
    for (int c = 0; c < nch; ++c) sum[std::size_t(c)] += double(t[c]) * count;
    covered += count;
  };
  if (shortcut) {
    int col[4] = {}, row[4] = {}, side[4] = {};
    bool in[4];
    const double cx[4] = {at(x, 0), at(x, s - 1), at(x, 0), at(x, s - 1)};
    const double cy[4] = {at(y, 0), at(y, 0), at(y, s - 1), at(y, s - 1)};
    for (int k = 0; k < 4; ++k) in[k] = look.texel(cx[k], cy[k], col[k], row[k], side[k]);
    if ((side[0] & side[1] & side[2] & side[3]) != 0) return;  // all beyond one side
    if (in[0] && in[1] && in[2] && in[3] && col[0] == col[1] && col[0] == col[2] &&
        col[0] == col[3] && row[0] == row[1] && row[0] == row[2] && row[0] == row[3]) {
      addTexel(col[0], row[0], s * s);
      return;
    }
  }
  for (int j = 0; j < s; ++j)
    for (int i = 0; i < s; ++i) {
      int col = 0, row = 0, side = 0;
      if (look.texel(at(x, i), at(y, j), col, row, side)) addTexel(col, row, 1);
    }
}

}  // namespace

void drawTexturedQuad(cv::Mat& image, const cv::Mat& texture, const cv::Matx33d& H,
                      int supersample) {
  drawTexturedQuadBlurred(image, texture, {H}, supersample);
}

void drawTexturedQuadBlurred(cv::Mat& image, const cv::Mat& texture,
                             const std::vector<cv::Matx33d>& Hs, int supersample, bool shortcut) {
  CV_Assert(image.depth() == CV_8U && texture.depth() == CV_8U);
  CV_Assert(texture.type() == image.type() || (texture.channels() == 1));
  CV_Assert(image.channels() <= kMaxChannels && !texture.empty());
  cv::Mat tex = texture;
  if (image.channels() == 3 && texture.channels() == 1)
    cv::cvtColor(texture, tex, cv::COLOR_GRAY2BGR);
  cv::Rect box;
  std::vector<TexelLookup> looks;
  for (const auto& H : Hs) {
    bool ok = false;
    const cv::Rect r = coveredBox(H, tex.size(), image.size(), ok);
    if (!ok) return;
    box = box.area() == 0 ? r : (box | r);
    looks.emplace_back(H.inv(), tex.size());
  }
  if (box.area() == 0) return;
  const int s = std::max(1, supersample), nch = image.channels();
  const double samples = double(Hs.size()) * s * s;
  for (int y = box.y; y < box.br().y; ++y) {
    std::uint8_t* px = image.ptr<std::uint8_t>(y);
    for (int x = box.x; x < box.br().x; ++x) {
      std::array<double, kMaxChannels> sum{};
      int covered = 0;
      for (const auto& look : looks) samplePixel(tex, look, x, y, s, shortcut, sum, covered);
      if (covered == 0) continue;
      // The texture premultiplied by its coverage, over the image: img (1 - a) + colour.
      const double a = covered / samples;
      std::uint8_t* p = px + std::size_t(x) * std::size_t(nch);
      for (int c = 0; c < nch; ++c)
        p[c] = cv::saturate_cast<std::uint8_t>(p[c] * (1 - a) + sum[std::size_t(c)] / samples);
    }
  }
}

}  // namespace ps::tracking
