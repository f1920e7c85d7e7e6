#include "render/image_compare.hpp"

#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace ps::render {

ImageDifference compareImages(const cv::Mat& image, const cv::Mat& reference, const cv::Mat& mask) {
  if (image.size() != reference.size() || image.type() != CV_8UC3 || reference.type() != CV_8UC3)
    throw std::invalid_argument("compareImages: two 8-bit BGR images of one size are needed");
  cv::Mat m = mask.empty() ? cv::Mat(image.size(), CV_8U, cv::Scalar(255)) : mask;
  if (m.size() != image.size() || m.type() != CV_8U)
    throw std::invalid_argument("compareImages: the mask must be 8-bit and the images' size");
  ImageDifference d;
  d.pixels = std::size_t(cv::countNonZero(m));
  if (d.pixels == 0) return d;
  cv::Mat diff;
  cv::absdiff(image, reference, diff);
  const cv::Scalar s = cv::mean(diff, m);
  d.meanAbsDiff = (s[0] + s[1] + s[2]) / 3;
  // SSIM on luma, in float.
  cv::Mat x, y;
  cv::cvtColor(image, x, cv::COLOR_BGR2GRAY);
  cv::cvtColor(reference, y, cv::COLOR_BGR2GRAY);
  x.convertTo(x, CV_32F);
  y.convertTo(y, CV_32F);
  constexpr double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  const cv::Size window(11, 11);
  auto blur = [&](const cv::Mat& a) {
    cv::Mat b;
    cv::GaussianBlur(a, b, window, 1.5);
    return b;
  };
  const cv::Mat mx = blur(x), my = blur(y);
  const cv::Mat mx2 = mx.mul(mx), my2 = my.mul(my), mxy = mx.mul(my);
  const cv::Mat sx2 = blur(x.mul(x)) - mx2, sy2 = blur(y.mul(y)) - my2, sxy = blur(x.mul(y)) - mxy;
  cv::Mat num = (2 * mxy + c1).mul(2 * sxy + c2), den = (mx2 + my2 + c1).mul(sx2 + sy2 + c2);
  cv::Mat ssim;
  cv::divide(num, den, ssim);
  d.ssim = cv::mean(ssim, m)[0];
  return d;
}

cv::Mat drawnMask(const cv::Mat& a, const cv::Mat& b, const cv::Vec3b& background) {
  cv::Mat ma, mb;
  cv::inRange(a, background, background, ma);
  cv::inRange(b, background, background, mb);
  return ~(ma & mb);
}

}  // namespace ps::render
