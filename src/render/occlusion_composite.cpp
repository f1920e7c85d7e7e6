#include "render/occlusion_composite.hpp"

#include <cmath>
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

void clearToolFromMask(cv::Mat& mask, const terrain::Camera& camera,
                       std::span<const Eigen::Vector3d> toolTriangles, int marginPx) {
  if (mask.empty() || toolTriangles.size() < 3) return;
  cv::Mat tool = cv::Mat::zeros(mask.size(), CV_8U);
  for (std::size_t i = 0; i + 2 < toolTriangles.size(); i += 3) {
    cv::Point corners[3];
    bool inFront = true;
    for (int k = 0; k < 3 && inFront; ++k) {
      const Eigen::Vector3d c = camera.rotation * (toolTriangles[i + k] - camera.eye);
      inFront = c.z() > 0;
      const Eigen::Vector2d p = inFront ? camera.project(c) : Eigen::Vector2d::Zero();
      corners[k] = cv::Point(int(std::lround(p.x())), int(std::lround(p.y())));
    }
    // A triangle reaching behind the camera is the stick's far end out of view: left out.
    if (inFront) cv::fillConvexPoly(tool, corners, 3, cv::Scalar(255));
  }
  if (marginPx > 0)
    cv::dilate(
        tool, tool,
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * marginPx + 1, 2 * marginPx + 1)));
  mask.setTo(0.0f, tool);
}

cv::Mat occludeByHand(const cv::Mat& view, const cv::Mat& camera, cv::Mat& mask,
                      const terrain::Camera& cam, std::span<const Eigen::Vector3d> toolTriangles) {
  if (mask.empty()) return {};
  clearToolFromMask(mask, cam, toolTriangles);
  if (cv::countNonZero(mask > 0.5f) == 0) return {};
  return composeOcclusion(view, camera, mask);
}

}  // namespace ps::render
