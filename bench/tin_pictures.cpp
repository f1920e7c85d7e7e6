#include "bench/tin_pictures.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace ps::bench {

namespace {

// Hill shading of the heightmap's samples in [x0, x0 + n)^2, `scale` pixels per sample, north up.
cv::Mat hillshade(const Heightmap& h, int x0, int y0, int n, int scale) {
  cv::Mat out(n * scale, n * scale, CV_8UC3);
  const Eigen::Vector3d sun = Eigen::Vector3d(-1, 1, 1.2).normalized();
  auto at = [&](int i, int j) {
    i = std::clamp(i, 0, h.side - 1), j = std::clamp(j, 0, h.side - 1);
    return double(h.heights[std::size_t(j) * std::size_t(h.side) + std::size_t(i)]);
  };
  for (int py = 0; py < n * scale; ++py)
    for (int px = 0; px < n * scale; ++px) {
      const int i = x0 + px / scale, j = y0 + (n - 1 - py / scale);
      const Eigen::Vector3d normal(-(at(i + 1, j) - at(i - 1, j)) / (2 * h.dx),
                                   -(at(i, j + 1) - at(i, j - 1)) / (2 * h.dy), 1.0);
      const double shade = std::clamp(normal.normalized().dot(sun), 0.0, 1.0);
      const auto g = std::uint8_t(60 + 180 * shade);
      out.at<cv::Vec3b>(py, px) = {g, g, g};
    }
  return out;
}

// Paper 001's picture: the control map (white: MinError) beside the TIN it gives, wireframe over
// hill shading, on a window across the control region's edge.
// The window [x0, x0 + n)^2 of lattice units, `scale` pixels each, north up.
struct Window {
  int x0, y0, n, scale;
  cv::Point2d pixel(const Eigen::Vector2d& p) const {
    return {(p.x() - x0 + 0.5) * scale, (n - 1 - (p.y() - y0) + 0.5) * scale};
  }
  bool touches(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    return !(std::max(a.x(), b.x()) < x0 || std::min(a.x(), b.x()) > x0 + n ||
             std::max(a.y(), b.y()) < y0 || std::min(a.y(), b.y()) > y0 + n);
  }
};

cv::Mat drawOverlay(const Heightmap& h, const tin::OverlayResult& r, const Window& w) {
  cv::Mat img = hillshade(h, w.x0, w.y0, w.n, w.scale);
  const auto& tin = r.tin;
  for (std::size_t k = 0; k < tin.triangles.size(); ++k) {
    if (!r.onRoad[k]) continue;
    const auto& t = tin.triangles[k];
    std::vector<cv::Point> poly;
    for (const auto v : t) {
      const cv::Point2d p = w.pixel(tin.xy[v]);
      poly.emplace_back(int(std::lround(p.x)), int(std::lround(p.y)));
    }
    cv::fillConvexPoly(img, poly, cv::Scalar(120, 200, 250), cv::LINE_AA);
  }
  for (std::size_t k = 0; k < tin.triangles.size(); ++k) {
    const auto& t = tin.triangles[k];
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector2d& a = tin.xy[t[std::size_t(e)]];
      const Eigen::Vector2d& b = tin.xy[t[std::size_t((e + 1) % 3)]];
      if (!w.touches(a, b)) continue;
      const cv::Scalar colour = r.onRoad[k] ? cv::Scalar(20, 40, 190) : cv::Scalar(90, 60, 40);
      cv::line(img, w.pixel(a), w.pixel(b), colour, 1, cv::LINE_AA);
    }
  }
  return img;
}

}  // namespace

void writeControlMapPicture(const Heightmap& h, const std::vector<bool>& inside, const tin::Tin& t,
                            const std::string& path) {
  const int n = std::min(h.side, 128), scale = 5;
  const int x0 =
      std::max(0, int(0.5 * (h.side - 1) - h.side * std::sqrt(1.0 / (6.0 * M_PI))) - n / 2);
  const int y0 = std::max(0, (h.side - n) / 2);
  cv::Mat left = hillshade(h, x0, y0, n, scale), right = left.clone();
  for (int py = 0; py < n * scale; ++py)
    for (int px = 0; px < n * scale; ++px) {
      const int i = x0 + px / scale, j = y0 + (n - 1 - py / scale);
      if (inside[std::size_t(j) * std::size_t(h.side) + std::size_t(i)]) {
        cv::Vec3b& c = left.at<cv::Vec3b>(py, px);
        for (int k = 0; k < 3; ++k) c[k] = std::uint8_t(155 + c[k] * 100 / 255);
      } else {
        cv::Vec3b& c = left.at<cv::Vec3b>(py, px);
        for (int k = 0; k < 3; ++k) c[k] = std::uint8_t(c[k] / 4);
      }
    }
  auto pixel = [&](const Eigen::Vector2d& p) {
    return cv::Point2d((p.x() - x0 + 0.5) * scale, (n - 1 - (p.y() - y0) + 0.5) * scale);
  };
  for (const auto& tri : t.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d& a = t.xy[tri[std::size_t(k)]];
      const Eigen::Vector2d& b = t.xy[tri[std::size_t((k + 1) % 3)]];
      if (std::max(a.x(), b.x()) < x0 || std::min(a.x(), b.x()) > x0 + n ||
          std::max(a.y(), b.y()) < y0 || std::min(a.y(), b.y()) > y0 + n)
        continue;
      cv::line(right, pixel(a), pixel(b), cv::Scalar(40, 90, 230), 1, cv::LINE_AA);
    }
  }
  cv::Mat both;
  cv::hconcat(left, cv::Mat(n * scale, 8, CV_8UC3, cv::Scalar(255, 255, 255)), both);
  cv::hconcat(both, right, both);
  cv::imwrite(path, both);
}

void writeOverlayPicture(const Heightmap& h, const tin::OverlayResult& stitched,
                         const tin::OverlayResult& stenciled, const std::string& path) {
  // Around the road: the bounding box of the stitched result's road triangles.
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (std::size_t k = 0; k < stitched.tin.triangles.size(); ++k)
    if (stitched.onRoad[k])
      for (const auto v : stitched.tin.triangles[k])
        lo = lo.cwiseMin(stitched.tin.xy[v]), hi = hi.cwiseMax(stitched.tin.xy[v]);
  const int n = std::min(h.side, 128), scale = 5;
  const Eigen::Vector2d c = 0.5 * (lo + hi);
  const Window w{std::clamp(int(c.x()) - n / 2, 0, h.side - n),
                 std::clamp(int(c.y()) - n / 2, 0, h.side - n), n, scale};
  cv::Mat both;
  cv::hconcat(drawOverlay(h, stitched, w),
              cv::Mat(n * scale, 8, CV_8UC3, cv::Scalar(255, 255, 255)), both);
  cv::hconcat(both, drawOverlay(h, stenciled, w), both);
  cv::imwrite(path, both);
}

}  // namespace ps::bench
