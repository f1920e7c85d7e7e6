// The renderer: projection math against OpenCV's pinhole, the float path against a double
// reference (planet scale, 1 m to 100,000 km), and on headless OpenGL (skipped with a message
// where EGL is missing): silhouette alignment with the analytic sphere, determinism, uploads
// only when the mesh changed, the picture against a sphere's known facts (silhouette radius,
// Lambert lighting, contours where the heights cross) and a golden image as a change detector
// only. The renderer in the AR frame (anchor, cursor, the tool's depth, the frame-to-frame
// skips) is test_render_ar_frame.cpp.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <string>

#include "app/build_paths.hpp"
#include "gl_test.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "terrain/tessellator.hpp"
#include "test_render_util.hpp"
#include "test_terrains.hpp"

using namespace ps;
using namespace ps::rendertest;

namespace {

// Settings fine enough that the outline is the sphere's within a fraction of a pixel.
terrain::TessellationSettings fineSettings() {
  terrain::TessellationSettings ts;
  ts.distMaxPx = 0.25;
  ts.triangleBudget = 0;
  return ts;
}

cv::Mat luma(const cv::Mat& bgr) {
  cv::Mat g;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  return g;
}

// The golden image as a change detector (llvmpipe's output of the bumpy view): any pixel off by
// more than 2 grey levels in a channel, or more than 0.2 % of the pixels changed at all, is a
// change. A change of the shading trips it (TheGoldenImageTripsOnAShadingChange).
testing::AssertionResult matchesGolden(const cv::Mat& image, const cv::Mat& golden) {
  if (golden.size() != image.size())
    return testing::AssertionFailure()
           << "golden image " << golden.size() << ", rendered " << image.size();
  cv::Mat diff;
  cv::absdiff(image, golden, diff);
  double largest = 0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &largest);
  const int changed = cv::countNonZero(luma(diff) > 0);
  if (largest <= 2 && changed <= int(0.002 * double(diff.total())))
    return testing::AssertionSuccess();
  return testing::AssertionFailure()
         << "differs from the golden image: largest channel difference " << largest << ", "
         << changed << " of " << diff.total() << " pixels changed";
}

// The bumpy view the golden image holds (DeterministicAndUploadsOnlyWhatChanged draws it).
cv::Mat bumpyView(render::PlanetRenderer& renderer, render::Shading shading) {
  auto planet = testkit::bumpyTerrain(8, 5, 8000.0);
  const auto cam = orbitCamera(1.6 * planet.chart().sphereRadius(), 240, 180);
  terrain::Tessellator tess;
  render::RenderStyle style;
  style.wireframe = true;
  style.contours = true;
  style.shading = shading;
  return renderer.renderAR({}, planet, tess.tessellate(planet, cam, {}), cam, style);
}

// The golden image holds llvmpipe's pixels; another rasteriser (a GPU's driver) differs by a
// level here and there, which is no change of ours.
bool drawnByLlvmpipe(const render::EglContext& gl) {
  if (gl.renderer().find("llvmpipe") != std::string::npos) return true;
  std::printf("golden image not compared: drawn by %s, not llvmpipe\n", gl.renderer().c_str());
  return false;
}

cv::Mat goldenImage() {
  return cv::imread((ps::app::sourceDir() / "tests/golden/render_bumpy.png").string(),
                    cv::IMREAD_COLOR);
}

}  // namespace

extern "C" int __lsan_is_turned_off() {
  return testkit::madeGlContext.load() ? 1 : 0;
}

TEST(RenderProjection, ClipSpaceLandsOnOpenCVPixels) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int k = 0; k < 200; ++k) {
    terrain::Camera c;
    c.width = 320 + int(300 * (U(rng) + 1));
    c.height = 240 + int(200 * (U(rng) + 1));
    c.fx = 400 + 200 * U(rng);
    c.fy = c.fx * (1 + 0.05 * U(rng));
    c.cx = 0.5 * c.width + 20 * U(rng);
    c.cy = 0.5 * c.height + 20 * U(rng);
    const Eigen::Vector3d X(U(rng), U(rng), 2 + U(rng));
    const Eigen::Matrix4d P = render::clipFromCamera(c, 0.5, 10);
    const Eigen::Vector4d clip = P * X.homogeneous();
    const double u = 0.5 * (clip.x() / clip.w() + 1) * c.width - 0.5;
    const double v = 0.5 * (1 - clip.y() / clip.w()) * c.height - 0.5;
    const Eigen::Vector2d expect = c.project(X);
    EXPECT_NEAR(u, expect.x(), 1e-9);
    EXPECT_NEAR(v, expect.y(), 1e-9);
    EXPECT_GT(clip.z() / clip.w(), -1);
    EXPECT_LT(clip.z() / clip.w(), 1);
  }
}

// Issue 9's planet-scale check: vertices of a 6,372.79 km planet through the renderer's float
// path land within 0.1 px of their double projection, from 1 m, 1 km and 100,000 km.
TEST(StressPlanetScale, FloatPathWithinATenthOfAPixelFrom1mTo100000km) {
  const auto planet = testkit::bumpyTerrain(9, 3, 6000.0);
  const core::Chart& chart = planet.chart();
  for (double altitude : {1.0, 1e3, 1e8}) {
    for (int spot = 0; spot < 3; ++spot) {
      const int u = 37 + 150 * spot, v = 100 + 80 * spot;
      const Eigen::Vector3d up = chart.up(u, v);
      const Eigen::Vector3d ground = chart.position(u, v, planet.height(u, v));
      const Eigen::Vector3d eye = ground + (altitude + 0.0) * up;
      Eigen::Vector3d tangent = up.unitOrthogonal();
      const Eigen::Vector3d target = altitude > 1e7
                                         ? Eigen::Vector3d::Zero()
                                         : Eigen::Vector3d(ground + 50 * altitude * tangent);
      const auto cam = terrain::Camera::lookAt(eye, target, up, 640, 480, 60 * M_PI / 180);
      terrain::Tessellator tess;
      terrain::TessellationSettings ts;
      ts.distMaxPx = 1;
      const auto& mesh = tess.tessellate(planet, cam, ts);
      ASSERT_GT(mesh.triangleCount(), 0u) << altitude;
      const auto depth = render::depthRangeFor(cam, planet);
      const Eigen::Matrix4d m = render::clipFromEyeRelative(
          render::clipFromCamera(cam, depth.nearZ, depth.farZ), cam.rotation, mesh.eye - cam.eye);
      double worst = 0;
      int checked = 0;
      const int side = planet.grid().side();
      for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const auto gi = mesh.gridIndex[i];
        const int gu = int(gi % std::uint64_t(side)), gv = int(gi / std::uint64_t(side));
        const Eigen::Vector3d X = cam.toCamera(chart.position(gu, gv, planet.height(gu, gv)));
        if (X.z() < depth.nearZ) continue;
        const Eigen::Vector2d exact = cam.project(X);
        if (std::abs(exact.x() - 320) > 640 || std::abs(exact.y() - 240) > 480) continue;
        const auto f = render::pixelThroughFloatPath(m, mesh.positions[i], 640, 480);
        ASSERT_TRUE(f.has_value());
        worst = std::max(worst, (*f - exact).norm());
        ++checked;
      }
      EXPECT_GT(checked, 10) << "altitude " << altitude;
      EXPECT_LT(worst, 0.1) << "altitude " << altitude << " m, spot " << spot;
    }
  }
}

TEST(RenderProjection, DepthRangeHoldsTheVisiblePlanet) {
  const auto planet = testkit::bumpyTerrain(7, 2, 8000.0);
  const double R = planet.chart().sphereRadius();
  for (double d : {1.2 * R, 3 * R, 100 * R}) {
    const auto cam = orbitCamera(d, 320, 240);
    const auto r = render::depthRangeFor(cam, planet);
    EXPECT_LT(r.nearZ, d - R - planet.maxHeight());
    EXPECT_GT(r.farZ, std::sqrt(d * d - R * R));  // the limb
    EXPECT_GT(r.nearZ, 0);
  }
}

// The rendered silhouette of a smooth sphere (all heights 0) matches the analytic one: every
// pixel whose centre ray hits the sphere with more than a pixel to spare is drawn, and none
// more than a pixel outside it.
TEST(RenderGl, SilhouetteMatchesTheAnalyticSphere) {
  SKIP_WITHOUT_GL();
  SmoothScene scene(8);
  const auto& mesh = scene.tess.tessellate(scene.planet, scene.cam, fineSettings());
  const cv::Mat drawn = luma(scene.renderer.renderAR({}, scene.planet, mesh, scene.cam, {})) > 0;
  cv::Mat analytic(scene.cam.height, scene.cam.width, CV_8U);
  for (int y = 0; y < scene.cam.height; ++y)
    for (int x = 0; x < scene.cam.width; ++x)
      analytic.at<uchar>(y, x) = sphereHit(scene.cam, scene.R, x, y) ? 255 : 0;
  cv::Mat grown, shrunk, outside, missing;
  cv::dilate(analytic, grown, cv::Mat::ones(3, 3, CV_8U));
  cv::erode(analytic, shrunk, cv::Mat::ones(3, 3, CV_8U));
  cv::bitwise_and(drawn, ~grown, outside);
  cv::bitwise_and(shrunk, ~drawn, missing);
  EXPECT_EQ(cv::countNonZero(outside), 0);
  EXPECT_EQ(cv::countNonZero(missing), 0);
  EXPECT_GT(cv::countNonZero(drawn), 5000);
}

TEST(RenderGl, DeterministicAndUploadsOnlyWhatChanged) {
  SKIP_WITHOUT_GL();
  BumpyScene scene(8, 5, 8000.0);
  render::PlanetRenderer renderer;
  const auto cam = orbitCamera(1.6 * scene.R, 240, 180);
  terrain::Tessellator tess;
  render::RenderStyle style;
  style.wireframe = true;
  style.contours = true;
  const cv::Mat a =
      renderer.renderAR({}, scene.planet, tess.tessellate(scene.planet, cam, {}), cam, style);
  EXPECT_EQ(renderer.stats().uploads, 1u);
  const cv::Mat b =
      renderer.renderAR({}, scene.planet, tess.tessellate(scene.planet, cam, {}), cam, style);
  EXPECT_TRUE(tess.stats().reused);
  EXPECT_EQ(renderer.stats().uploads, 1u);  // same view, same terrain: nothing sent
  EXPECT_FALSE(renderer.stats().uploadedThisFrame);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  // A changed view re-tessellates and uploads; the image changes.
  const auto cam2 = orbitCamera(1.5 * scene.R, 240, 180);
  const cv::Mat c =
      renderer.renderAR({}, scene.planet, tess.tessellate(scene.planet, cam2, {}), cam2, style);
  EXPECT_EQ(renderer.stats().uploads, 2u);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);

  // The golden image (llvmpipe) detects changes only; what the picture must be is checked
  // against the sphere below. Regenerate it with PS_UPDATE_GOLDEN=1 after an intended change.
  if (!drawnByLlvmpipe(scene.gl)) return;
  if (std::getenv("PS_UPDATE_GOLDEN"))
    cv::imwrite((ps::app::sourceDir() / "tests/golden/render_bumpy.png").string(), a);
  const cv::Mat g = goldenImage();
  ASSERT_FALSE(g.empty()) << "tests/golden/render_bumpy.png";
  EXPECT_TRUE(matchesGolden(a, g));
}

// The change detector is tight enough to see a change of the shading: the same view drawn with
// faceted shading (what per-pixel shading replaced) does not match the golden image.
TEST(RenderGl, TheGoldenImageTripsOnAShadingChange) {
  SKIP_WITHOUT_GL();
  render::EglContext gl;
  if (!drawnByLlvmpipe(gl))
    GTEST_SKIP() << "the golden image is llvmpipe's; this is " << gl.renderer();
  render::PlanetRenderer renderer;
  const cv::Mat g = goldenImage();
  ASSERT_FALSE(g.empty()) << "tests/golden/render_bumpy.png";
  ASSERT_TRUE(matchesGolden(bumpyView(renderer, render::Shading::kPerPixel), g));
  const auto faceted = matchesGolden(bumpyView(renderer, render::Shading::kFaceted), g);
  EXPECT_FALSE(faceted);
  std::printf("faceted against the golden image: %s\n", faceted.message());
}

// A planet of constant height h is a sphere of radius R + h: seen from a camera looking at its
// centre, a disc about the principal point of radius f tan(asin((R + h) / d)). Every pixel
// farther than 1 px outside that circle is empty and every pixel more than 1 px inside is drawn.
TEST(RenderGl, AConstantHeightPlanetIsADiscOfTheSpheresProjectedRadius) {
  SKIP_WITHOUT_GL();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  for (const float h : {0.0f, 250e3f}) {
    const terrain::Terrain planet = smoothPlanet(8, h);
    const double r = planet.chart().sphereRadius() + h;
    const auto cam = orbitCamera(5 * r, 320, 240);
    ASSERT_EQ(cam.fx, cam.fy);
    terrain::Tessellator tess;
    const cv::Mat drawn =
        luma(renderer.renderAR({}, planet, tess.tessellate(planet, cam, fineSettings()), cam, {})) >
        0;
    const double rho = cam.fx * std::tan(std::asin(r / cam.eye.norm()));
    int inside = 0, outside = 0, count = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const double off = std::hypot(x - cam.cx, y - cam.cy);
        const bool on = drawn.at<uchar>(y, x) != 0;
        count += on;
        outside += on && off > rho + 1;
        inside += !on && off < rho - 1;
      }
    EXPECT_EQ(outside, 0) << "height " << h << ": drawn pixels beyond " << rho << " + 1 px";
    EXPECT_EQ(inside, 0) << "height " << h << ": empty pixels within " << rho << " - 1 px";
    EXPECT_NEAR(std::sqrt(count / M_PI), rho, 1.0) << "height " << h;
  }
}

// Lambert's law on a smooth sphere: with the sun to the side, the half that faces it is lit and
// the far half gets the ambient light only; the brightness rises with the cosine of the sun's
// angle at the surface point (the reference's normal), and turning the sun round turns the
// picture round.
TEST(RenderGl, TheSunLightsTheSideThatFacesIt) {
  SKIP_WITHOUT_GL();
  SmoothScene scene(8);
  const auto& mesh = scene.tess.tessellate(scene.planet, scene.cam, {});
  const Eigen::Vector3d side = scene.cam.eye.cross(Eigen::Vector3d::UnitZ()).normalized();
  for (const double sign : {1.0, -1.0}) {
    render::RenderStyle style;
    style.sun = sign * side;
    const cv::Mat grey = luma(scene.renderer.renderAR({}, scene.planet, mesh, scene.cam, style));
    double facing = 0, far = 0;
    int nFacing = 0, nFar = 0;
    std::vector<double> lambert, value;
    for (int y = 0; y < scene.cam.height; ++y)
      for (int x = 0; x < scene.cam.width; ++x) {
        if (!sphereHit(scene.cam, 0.98 * scene.R, x, y)) continue;  // inside the limb by a margin
        const auto p = sphereHit(scene.cam, scene.R, x, y);
        const double c = p->normalized().dot(style.sun), g = grey.at<uchar>(y, x);
        if (c > 0.5) facing += g, ++nFacing;
        if (c < -0.2) far += g, ++nFar;
        lambert.push_back(std::max(c, 0.0));
        value.push_back(g);
      }
    ASSERT_GT(nFacing, 1000);
    ASSERT_GT(nFar, 1000);
    EXPECT_GT(facing / nFacing, 2.0 * (far / nFar)) << "sun " << style.sun.transpose();
    cv::Scalar mean[2], deviation[2];
    cv::meanStdDev(lambert, mean[0], deviation[0]);
    cv::meanStdDev(value, mean[1], deviation[1]);
    double covariance = 0;
    for (std::size_t k = 0; k < value.size(); ++k)
      covariance += (lambert[k] - mean[0][0]) * (value[k] - mean[1][0]);
    const double correlation =
        covariance / double(value.size()) / (deviation[0][0] * deviation[1][0]);
    EXPECT_GT(correlation, 0.98) << "brightness against max(cos, 0): not Lambert's";
  }
}

// Contour lines lie where the heights cross their levels: on a sphere whose height is
// 5,000 m x sin(latitude), every pixel the lines darken is within 3 pixel steps of a multiple of
// the interval (a step: the reference height's largest change to a neighbouring pixel; a line
// fades out 1.5 x (|dh/dx| + |dh/dy|) from its level, up to 3 steps), and nearly every pair of
// neighbouring pixels that a level passes between is darkened.
TEST(RenderGl, ContourLinesLieWhereTheHeightsCrossTheirLevels) {
  SKIP_WITHOUT_GL();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  auto chart = testkit::earthChart(8);
  constexpr double kAmplitude = 5000, kInterval = 1000;
  std::vector<float> heights(chart->grid().count());
  for (int v = 0; v <= chart->grid().m(); ++v)
    for (int u = 0; u <= chart->grid().m(); ++u)
      heights[chart->grid().index(u, v)] =
          float(kAmplitude * chart->position(u, v, 0.0).normalized().z());
  const terrain::Terrain planet(chart, heights);
  const double R = chart->sphereRadius();
  const auto cam = orbitCamera(3 * R, 320, 240);
  terrain::Tessellator tess;
  const auto& mesh = tess.tessellate(planet, cam, {});
  render::RenderStyle style;
  style.sun = cam.eye.normalized();
  style.contourIntervalM = kInterval;
  const cv::Mat plain = luma(renderer.renderAR({}, planet, mesh, cam, style));
  style.contours = true;
  const cv::Mat lined = luma(renderer.renderAR({}, planet, mesh, cam, style));
  // Reference heights per pixel, NaN off the sphere or near its limb.
  cv::Mat H(cam.height, cam.width, CV_64F, cv::Scalar(NAN));
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      if (const auto p = sphereHit(cam, R, x, y);
          p && p->normalized().dot((cam.eye - *p).normalized()) > 0.3)
        H.at<double>(y, x) = kAmplitude * p->normalized().z();
  auto darkened = [&](int x, int y) { return lined.at<uchar>(y, x) + 6 < plain.at<uchar>(y, x); };
  int dark = 0, farFromLevel = 0, crossings = 0, crossingsLined = 0;
  for (int y = 1; y + 1 < cam.height; ++y)
    for (int x = 1; x + 1 < cam.width; ++x) {
      const double h = H.at<double>(y, x);
      if (std::isnan(h)) continue;
      double step = 0;  // the height's largest change to a neighbouring pixel
      for (const auto& [dx, dy] :
           {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        const double n = H.at<double>(y + dy, x + dx);
        if (!std::isnan(n)) step = std::max(step, std::abs(n - h));
      }
      const double toLevel = std::abs(h - kInterval * std::round(h / kInterval));
      if (darkened(x, y)) {
        ++dark;
        farFromLevel += toLevel > 3 * step;
      }
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}}) {
        const double n = H.at<double>(y + dy, x + dx);
        if (std::isnan(n) || std::floor(h / kInterval) == std::floor(n / kInterval)) continue;
        ++crossings;
        crossingsLined += darkened(x, y) || darkened(x + dx, y + dy);
      }
    }
  EXPECT_GT(dark, 500);
  EXPECT_EQ(farFromLevel, 0) << "of " << dark << " darkened pixels";
  EXPECT_GT(crossings, 500);
  EXPECT_GE(crossingsLined, 0.97 * crossings) << crossingsLined << " of " << crossings;
}
