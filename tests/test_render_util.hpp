#pragma once
// The scenes the renderer's tests draw (test_render.cpp, test_render_ar_frame.cpp): a camera in
// orbit, a smooth and a bumpy planet with a GL context, and a pixel's ray with where it meets a
// sphere (the reference the pictures are checked against).
#include <cmath>
#include <optional>

#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"

namespace ps::rendertest {

inline terrain::Camera orbitCamera(double distance, int w, int h, double fovDeg = 40) {
  return terrain::Camera::lookAt(Eigen::Vector3d(distance, 0.3 * distance, 0.2 * distance),
                                 Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), w, h,
                                 fovDeg * M_PI / 180);
}

// A sphere with every height `h`: its silhouette and surface are known exactly.
inline terrain::Terrain smoothPlanet(int n, float h = 0.0f) {
  auto chart = testkit::earthChart(n);
  return terrain::Terrain(chart, std::vector<float>(chart->grid().count(), h));
}

// Where pixel (x, y)'s ray meets the sphere of radius r about the origin (the nearer point), or
// nothing: the reference the renderer's pictures are checked against.
// The unit direction (planet frame) of the ray through pixel (x, y)'s centre.
inline Eigen::Vector3d pixelRay(const terrain::Camera& cam, int x, int y) {
  return (cam.rotation.transpose() *
          Eigen::Vector3d((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1))
      .normalized();
}

inline std::optional<Eigen::Vector3d> sphereHit(const terrain::Camera& cam, double r, int x,
                                                int y) {
  const Eigen::Vector3d d = pixelRay(cam, x, y);
  const double along = -cam.eye.dot(d), miss2 = (cam.eye + along * d).squaredNorm();
  if (along <= 0 || miss2 >= r * r) return std::nullopt;
  return cam.eye + (along - std::sqrt(r * r - miss2)) * d;
}

// The smooth planet of 2^n + 1 squared heights from 3 radii away at 320 x 240, with a GL
// context, a renderer and a tessellator (make it after SKIP_WITHOUT_GL).
struct SmoothScene {
  explicit SmoothScene(int n)
      : planet(smoothPlanet(n)),
        R(planet.chart().sphereRadius()),
        cam(orbitCamera(3 * R, 320, 240)) {}
  const terrain::Terrain planet;
  const double R;
  const terrain::Camera cam;
  render::EglContext gl;
  render::PlanetRenderer renderer;
  terrain::Tessellator tess;
};

// A bumpy planet (testkit::bumpyTerrain(n, seed, amplitude)) with a GL context (make it after
// SKIP_WITHOUT_GL).
struct BumpyScene {
  BumpyScene(int n, std::uint32_t seed, double amplitude)
      : planet(testkit::bumpyTerrain(n, seed, amplitude)), R(planet.chart().sphereRadius()) {}
  terrain::Terrain planet;
  const double R;
  render::EglContext gl;
};

}  // namespace ps::rendertest
