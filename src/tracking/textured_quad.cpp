#include "tracking/textured_quad.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace ps::tracking {

namespace {

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

// A matrix over storage kept between calls. A board's card at 8x supersampling fills tens of
// megabytes, and a fresh allocation that large is a fresh mapping whose every page faults in on
// first touch: most of a synthetic frame's time went there (under the sanitizers, whose
// allocator maps and unmaps every large block, a third of the tracking tests' run, docs/CI.md).
// Kept per thread up to 96 MB a buffer (a card over most of a 640x480 frame); larger ones are
// made afresh, as before.
cv::Mat kept(std::vector<std::uint8_t>& storage, cv::Size size, int type) {
  const std::size_t bytes = std::size_t(size.area()) * std::size_t(CV_ELEM_SIZE(type));
  if (bytes > (std::size_t(96) << 20)) return cv::Mat(size, type);
  if (storage.size() < bytes) storage.resize(bytes);
  return cv::Mat(size, type, storage.data());
}

// Coverage (CV_32F, 0..1) and colour (CV_32FC(n)) of the quad in box `roi` of the image.
void renderBox(const cv::Mat& texture, const cv::Matx33d& H, cv::Rect roi, int s, cv::Mat& colour,
               cv::Mat& alpha) {
  thread_local std::vector<std::uint8_t> colour8, colour32, cover8, cover32;
  // Supersampled pixel (xs, ys) has its centre at image x = roi.x + (xs + 0.5) / s - 0.5.
  const double is = 1.0 / s;
  const cv::Matx33d A(is, 0, roi.x + 0.5 * is - 0.5, 0, is, roi.y + 0.5 * is - 0.5, 0, 0, 1);
  // Texel index coordinates are continuous texture coordinates minus 0.5.
  const cv::Matx33d shift(1, 0, -0.5, 0, 1, -0.5, 0, 0, 1);
  const cv::Matx33d M = shift * H.inv() * A;  // supersampled pixel -> texel index
  const cv::Size big(roi.width * s, roi.height * s);
  const cv::Mat ones(texture.size(), CV_8U, cv::Scalar(255));
  cv::Mat c = kept(colour8, big, texture.type()), a = kept(cover8, big, CV_8U);
  cv::Mat c32 = kept(colour32, big, CV_32FC(texture.channels())), a32 = kept(cover32, big, CV_32F);
  cv::warpPerspective(texture, c, M, big, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar::all(0));
  cv::warpPerspective(ones, a, M, big, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  c.convertTo(c32, CV_32F);
  a.convertTo(a32, CV_32F, 1.0 / 255);
  cv::resize(c32, colour, roi.size(), 0, 0, cv::INTER_AREA);
  cv::resize(a32, alpha, roi.size(), 0, 0, cv::INTER_AREA);
}

void blend(cv::Mat& image, cv::Rect roi, const cv::Mat& colour, const cv::Mat& alpha) {
  // colour is premultiplied by coverage (texture * mask averaged): out = img * (1 - a) + colour.
  cv::Mat dst = image(roi), d32;
  dst.convertTo(d32, CV_32F);
  cv::Mat a = alpha;
  if (d32.channels() == 3) cv::merge(std::vector<cv::Mat>{alpha, alpha, alpha}, a);
  cv::Mat inv;
  cv::subtract(cv::Scalar::all(1.0), a, inv);  // (1.0 - a would only fill the first channel)
  cv::Mat out = d32.mul(inv) + colour;
  out.convertTo(dst, image.type());
}

}  // namespace

void drawTexturedQuad(cv::Mat& image, const cv::Mat& texture, const cv::Matx33d& H,
                      int supersample) {
  drawTexturedQuadBlurred(image, texture, {H}, supersample);
}

void drawTexturedQuadBlurred(cv::Mat& image, const cv::Mat& texture,
                             const std::vector<cv::Matx33d>& Hs, int supersample) {
  CV_Assert(texture.type() == image.type() || (texture.channels() == 1));
  cv::Mat tex = texture;
  if (image.channels() == 3 && texture.channels() == 1)
    cv::cvtColor(texture, tex, cv::COLOR_GRAY2BGR);
  cv::Rect box;
  for (const auto& H : Hs) {
    bool ok = false;
    const cv::Rect r = coveredBox(H, tex.size(), image.size(), ok);
    if (!ok) return;
    box = box.area() == 0 ? r : (box | r);
  }
  if (box.area() == 0) return;
  cv::Mat colourSum, alphaSum;
  for (const auto& H : Hs) {
    cv::Mat c, a;
    renderBox(tex, H, box, std::max(1, supersample), c, a);
    // Premultiply: the warped texture is already 0 outside the quad (border 0).
    if (colourSum.empty()) {
      colourSum = c;
      alphaSum = a;
    } else {
      colourSum += c;
      alphaSum += a;
    }
  }
  const double n = double(Hs.size());
  colourSum /= n;
  alphaSum /= n;
  blend(image, box, colourSum, alphaSum);
}

}  // namespace ps::tracking
