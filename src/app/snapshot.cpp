#include "app/snapshot.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "io/heightmap_export.hpp"

namespace ps::app {

namespace {

// The previews' hypsometric ramp (io::hypsometricTint), BGR in 0..1.
Eigen::Vector3f tint(double h) {
  const cv::Vec3f c = io::hypsometricTint(h) / 255.0f;
  return {c[0], c[1], c[2]};
}

}  // namespace

cv::Mat renderSnapshot(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
                       const terrain::Camera& camera, bool wireframe) {
  const int W = camera.width, H = camera.height;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(25, 12, 8));
  std::vector<float> zbuf(std::size_t(W) * std::size_t(H), INFINITY);
  const std::size_t nv = mesh.positions.size();
  std::vector<Eigen::Vector3d> cam(nv);
  std::vector<Eigen::Vector2d> px(nv);
  std::vector<Eigen::Vector3f> colour(nv);
  const auto side = std::uint64_t(terrain.grid().side());
  for (std::size_t i = 0; i < nv; ++i) {
    cam[i] = camera.rotation * mesh.positions[i].cast<double>();
    px[i] = cam[i].z() > 1e-6 ? camera.project(cam[i]) : Eigen::Vector2d(NAN, NAN);
    const auto gi = mesh.gridIndex[i];
    colour[i] = tint(terrain.height(int(gi % side), int(gi / side)));
  }
  // A low sun from the camera's upper left, so relief reads in any view.
  const Eigen::Vector3d right = camera.rotation.row(0).transpose(),
                        down = camera.rotation.row(1).transpose(),
                        forward = camera.rotation.row(2).transpose();
  const Eigen::Vector3d sun = (-0.7 * right - 0.5 * down - 0.5 * forward).normalized();
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const std::uint32_t ia = mesh.indices[3 * t], ib = mesh.indices[3 * t + 1],
                        ic = mesh.indices[3 * t + 2];
    if (!(cam[ia].z() > 1e-3 && cam[ib].z() > 1e-3 && cam[ic].z() > 1e-3))
      continue;  // no near clipping: drop
    const Eigen::Vector3d pa = mesh.positions[ia].cast<double>(),
                          pb = mesh.positions[ib].cast<double>(),
                          pc = mesh.positions[ic].cast<double>();
    Eigen::Vector3d n = (pb - pa).cross(pc - pa);
    if (!(n.norm() > 0) || n.dot(pa) >= 0) continue;  // degenerate or facing away
    n.normalize();
    const float shade = float(0.25 + 0.85 * std::max(0.0, n.dot(sun)));
    const Eigen::Vector2d a = px[ia], b = px[ib], c = px[ic];
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()})))),
              x1 = std::min(W - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({a.y(), b.y(), c.y()})))),
              y1 = std::min(H - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    // Perspective-correct interpolation of 1/z and colour/z.
    const double iza = 1 / cam[ia].z(), izb = 1 / cam[ib].z(), izc = 1 / cam[ic].z();
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d p(x, y);
        const double w0 = ((b - p).x() * (c - p).y() - (b - p).y() * (c - p).x()) / area;
        const double w1 = ((c - p).x() * (a - p).y() - (c - p).y() * (a - p).x()) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double iz = w0 * iza + w1 * izb + w2 * izc;
        const float z = float(1 / iz);
        float& zb = zbuf[std::size_t(y) * std::size_t(W) + std::size_t(x)];
        if (z >= zb) continue;
        zb = z;
        const Eigen::Vector3f col =
            shade * (float(w0 * iza / iz) * colour[ia] + float(w1 * izb / iz) * colour[ib] +
                     float(w2 * izc / iz) * colour[ic]);
        img.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(255 * col.x()),
                                            cv::saturate_cast<uchar>(255 * col.y()),
                                            cv::saturate_cast<uchar>(255 * col.z()));
      }
    }
  }
  if (wireframe) {
    cv::Mat lines = img.clone();
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
      const std::uint32_t idx[3] = {mesh.indices[3 * t], mesh.indices[3 * t + 1],
                                    mesh.indices[3 * t + 2]};
      if (!(cam[idx[0]].z() > 1e-3 && cam[idx[1]].z() > 1e-3 && cam[idx[2]].z() > 1e-3)) continue;
      const Eigen::Vector3d pa = mesh.positions[idx[0]].cast<double>();
      const Eigen::Vector3d n = (mesh.positions[idx[1]].cast<double>() - pa)
                                    .cross(mesh.positions[idx[2]].cast<double>() - pa);
      if (n.dot(pa) >= 0) continue;
      for (int e = 0; e < 3; ++e) {
        const Eigen::Vector2d p = px[idx[e]], q = px[idx[(e + 1) % 3]];
        if (std::abs(p.x()) > 1e5 || std::abs(p.y()) > 1e5 || std::abs(q.x()) > 1e5 ||
            std::abs(q.y()) > 1e5)
          continue;
        cv::line(lines, cv::Point2d(p.x(), p.y()), cv::Point2d(q.x(), q.y()),
                 cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
      }
    }
    cv::addWeighted(lines, 0.55, img, 0.45, 0, img);
  }
  return img;
}

}  // namespace ps::app
