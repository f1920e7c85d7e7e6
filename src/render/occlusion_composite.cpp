#include "render/occlusion_composite.hpp"

#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace ps::render {

cv::Mat composeOcclusion(const cv::Mat& view, const cv::Mat& camera, const cv::Mat& mask) {
  if (mask.empty()) return view;
  if (view.type() != CV_8UC3 || mask.type() != CV_32F || view.size() != mask.size() ||
      camera.size() != view.size() || camera.depth() != CV_8U ||
      (camera.channels() != 1 && camera.channels() != 3))
    throw std::invalid_argument(
        "composeOcclusion: the view (BGR 8-bit), the camera image (8-bit) and the mask (32-bit "
        "float) must have one size");
  // Only the mask's bounding box changes (a hand covers a small part of the frame).
  cv::Mat nonzero = mask > 1e-3f;
  const cv::Rect box = cv::boundingRect(nonzero);
  if (box.area() == 0) return view;
  cv::Mat out = view.clone();
  cv::Mat cam;
  if (camera.channels() == 1)
    cv::cvtColor(camera(box), cam, cv::COLOR_GRAY2BGR);
  else
    cam = camera(box);
  cv::Mat a, v, c;
  cv::merge(std::vector<cv::Mat>(3, cv::Mat(mask(box))), a);
  view(box).convertTo(v, CV_32FC3);
  cam.convertTo(c, CV_32FC3);
  cv::Mat blend = v + a.mul(c - v);
  blend.convertTo(out(box), CV_8UC3);
  return out;
}

}  // namespace ps::render
