// The renderer: projection math against OpenCV's pinhole, the float path against a double
// reference (planet scale, 1 m to 100,000 km), and on headless OpenGL (skipped with a message
// where EGL is missing): silhouette alignment with the analytic sphere, determinism, uploads
// only when the mesh changed, a golden image, and the AR anchor on a synthetic marker frame.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "app/build_paths.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "gl_test.hpp"
#include "render/changed_ranges.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"
#include "tracking/detector.hpp"
#include "tracking/pose.hpp"
#include "tracking/synth.hpp"
#include "tracking/tool_shape.hpp"
#include "tracking/tracker.hpp"

using namespace ps;

namespace {

terrain::Camera orbitCamera(double distance, int w, int h, double fovDeg = 40) {
  return terrain::Camera::lookAt(Eigen::Vector3d(distance, 0.3 * distance, 0.2 * distance),
                                 Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), w, h,
                                 fovDeg * M_PI / 180);
}

// A sphere with every height 0: its silhouette and surface are known exactly.
terrain::Terrain smoothPlanet(int n) {
  auto chart = testkit::earthChart(n);
  return terrain::Terrain(chart, std::vector<float>(chart->grid().count(), 0.0f));
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
  const double R = planet.chart().radius();
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
  const terrain::Terrain planet = smoothPlanet(8);
  const core::Chart* chart = &planet.chart();
  const double R = chart->radius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  const auto cam = orbitCamera(3 * R, 320, 240);
  terrain::Tessellator tess;
  terrain::TessellationSettings ts;
  ts.distMaxPx = 0.25;
  ts.triangleBudget = 0;
  const auto& mesh = tess.tessellate(planet, cam, ts);
  const cv::Mat img = renderer.renderAR({}, planet, mesh, cam, {});
  cv::Mat drawn, analytic(cam.height, cam.width, CV_8U);
  cv::cvtColor(img, drawn, cv::COLOR_BGR2GRAY);
  drawn = drawn > 0;
  const Eigen::Matrix3d Rt = cam.rotation.transpose();
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const Eigen::Vector3d d =
          (Rt * Eigen::Vector3d((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1)).normalized();
      const double along = -cam.eye.dot(d);
      const double miss = (cam.eye + along * d).norm();
      analytic.at<uchar>(y, x) = (along > 0 && miss < R) ? 255 : 0;
    }
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
  auto planet = testkit::bumpyTerrain(8, 5, 8000.0);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  const auto cam = orbitCamera(1.6 * R, 240, 180);
  terrain::Tessellator tess;
  render::RenderStyle style;
  style.wireframe = true;
  style.contours = true;
  const cv::Mat a = renderer.renderAR({}, planet, tess.tessellate(planet, cam, {}), cam, style);
  EXPECT_EQ(renderer.stats().uploads, 1u);
  const cv::Mat b = renderer.renderAR({}, planet, tess.tessellate(planet, cam, {}), cam, style);
  EXPECT_TRUE(tess.stats().reused);
  EXPECT_EQ(renderer.stats().uploads, 1u);  // same view, same terrain: nothing sent
  EXPECT_FALSE(renderer.stats().uploadedThisFrame);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  // A changed view re-tessellates and uploads; the image changes.
  const auto cam2 = orbitCamera(1.5 * R, 240, 180);
  const cv::Mat c = renderer.renderAR({}, planet, tess.tessellate(planet, cam2, {}), cam2, style);
  EXPECT_EQ(renderer.stats().uploads, 2u);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);

  // Golden image (llvmpipe): regenerate with PS_UPDATE_GOLDEN=1 after an intended change.
  const auto golden = ps::app::sourceDir() / "tests/golden/render_bumpy.png";
  if (std::getenv("PS_UPDATE_GOLDEN")) cv::imwrite(golden.string(), a);
  const cv::Mat g = cv::imread(golden.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(g.empty()) << golden;
  ASSERT_EQ(g.size(), a.size());
  cv::Mat diff;
  cv::absdiff(a, g, diff);
  EXPECT_LT(cv::mean(diff)[0] + cv::mean(diff)[1] + cv::mean(diff)[2], 3.0);
  cv::Mat big;
  cv::cvtColor(diff, big, cv::COLOR_BGR2GRAY);
  EXPECT_LT(cv::countNonZero(big > 24), int(0.01 * double(big.total())));
}

// The AR anchor: on a synthetic frame, the planet's contact point (its south pole in the planet
// frame sits on the planet marker's centre) projects onto the detected marker's centre (the
// crossing of its diagonals) within 1 px, through the renderer's matrices.
TEST(RenderGl, PlanetAnchorLandsOnTheDetectedMarker) {
  auto script = tracking::builtinScene("still");
  script.colour = false;
  // The tool off to the side (lat 10, lon 0): in the built-in pose its stick crosses the
  // planet marker.
  for (auto& k : script.keys) k.tipLatDeg = 10, k.tipLonDeg = 0;
  const tracking::SynthRenderer synth(script);
  const cv::Mat frame = synth.render(0);
  tracking::DetectorConfig dc;
  dc.regions = false;
  dc.ids = {script.planetId};
  const auto found = tracking::makeDetector(dc)->detect(frame);
  ASSERT_EQ(found.size(), 1u);
  const auto& q = found[0].corners;
  // Diagonal crossing of the detected quad.
  const cv::Point2d a = q[0], b = q[2], c = q[1], d = q[3];
  const cv::Point2d r = b - a, s = d - c;
  const double t = ((c - a).x * s.y - (c - a).y * s.x) / (r.x * s.y - r.y * s.x);
  const cv::Point2d centre = a + t * r;

  tracking::SceneConfig sc;
  sc.planet.filter = false;
  sc.planet.id = script.planetId;
  sc.planet.size = script.planetMarkerSize;
  sc.planetRadius = script.planetRadius;
  tracking::SceneTracker scene(sc);
  const auto f = scene.update(found, script.camera, 0, 0.0);
  ASSERT_TRUE(f.planet.usable());
  const tracking::Pose planetPose = scene.planetFromMarker(f.planet.pose);
  const double R = testkit::kEarthRadius, scale = R / sc.planetRadius;
  Eigen::Matrix3d K;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) K(i, j) = script.camera.K(i, j);
  const auto cam = render::arCamera(planetPose.R, planetPose.t, scale, K, frame.cols, frame.rows);
  const Eigen::Matrix4d m = render::clipFromEyeRelative(render::clipFromCamera(cam, 1e3, 1e9),
                                                        cam.rotation, Eigen::Vector3d::Zero());
  const Eigen::Vector3d southPole(0, 0, -R);
  const auto px =
      render::pixelThroughFloatPath(m, (southPole - cam.eye).cast<float>(), frame.cols, frame.rows);
  ASSERT_TRUE(px.has_value());
  EXPECT_LT(std::hypot(px->x() - centre.x, px->y() - centre.y), 1.0)
      << "anchor " << px->transpose() << " marker centre " << centre;
}

// The cursor: the ring of r_d around the control vertex and the force arrow are drawn where
// they are (the arrow across the view, in its own colour).
TEST(RenderGl, CursorRingAndForceArrowAreDrawn) {
  SKIP_WITHOUT_GL();
  const terrain::Terrain planet = smoothPlanet(7);
  const core::Chart* chart = &planet.chart();
  const double R = chart->radius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  const auto cam = orbitCamera(3 * R, 320, 240);
  terrain::Tessellator tess;
  const auto& mesh = tess.tessellate(planet, cam, {});
  // The vertex facing the camera most directly.
  const int side = chart->grid().side();
  core::GridPoint best;
  double bestDot = -2;
  for (int v = 1; v < side - 1; v += 4)
    for (int u = 0; u < side - 1; u += 4) {
      const double d = chart->up(u, v).dot(cam.eye.normalized());
      if (d > bestDot) bestDot = d, best = {u, v};
    }
  render::Cursor c{best, 0.2 * R};
  const Eigen::Vector3d n = chart->up(best.u, best.v);
  c.arrowFrom = R * n;
  c.arrow = 0.5 * R * n.cross(Eigen::Vector3d::UnitZ()).normalized();  // across the view
  const cv::Mat img = renderer.renderAR({}, planet, mesh, cam, {}, c);
  cv::Mat ring, arrow;
  cv::inRange(img, cv::Scalar(0, 200, 240), cv::Scalar(60, 240, 255), ring);   // (1, .85, .1)
  cv::inRange(img, cv::Scalar(50, 240, 30), cv::Scalar(100, 255, 80), arrow);  // (.2, 1, .3)
  EXPECT_GT(cv::countNonZero(ring), 100);
  EXPECT_GT(cv::countNonZero(arrow), 40);
  // Without an arrow, no arrow colour anywhere.
  c.arrow.setZero();
  const cv::Mat none = renderer.renderAR({}, planet, mesh, cam, {}, c);
  cv::inRange(none, cv::Scalar(50, 240, 30), cv::Scalar(100, 255, 80), arrow);
  EXPECT_EQ(cv::countNonZero(arrow), 0);
}

// The tool's depth pass (render/occluder_pass.hpp): a stick of known radius across the view in
// front of a planet of known radius hides the planet exactly where a ray meets the stick first
// (the camera image shows there, pixel for pixel), and nowhere else; the same stick behind the
// planet, or nearer the camera than the planet's near plane, is judged the same way.
TEST(RenderGl, TheToolHidesThePlanetExactlyWhereItIsInFront) {
  SKIP_WITHOUT_GL();
  const terrain::Terrain planet = smoothPlanet(7);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  const auto cam = orbitCamera(3 * R, 320, 240);
  terrain::Tessellator tess;
  terrain::TessellationSettings ts;
  ts.distMaxPx = 0.5;
  const auto& mesh = tess.tessellate(planet, cam, ts);
  const cv::Vec3b camColour(255, 0, 255);  // the "camera image": no planet pixel has it
  const cv::Mat background(cam.height, cam.width, CV_8UC3, cv::Scalar(camColour));
  const cv::Mat bare = renderer.renderAR(background, planet, mesh, cam, {});
  cv::Mat planetPixels;
  cv::inRange(bare, cv::Scalar(camColour), cv::Scalar(camColour), planetPixels);
  planetPixels = ~planetPixels;
  ASSERT_GT(cv::countNonZero(planetPixels), 5000);
  const Eigen::Matrix3d Rt = cam.rotation.transpose();
  const Eigen::Vector3d toCam = cam.eye.normalized();
  const Eigen::Vector3d across = toCam.cross(Eigen::Vector3d::UnitZ()).normalized();
  const double radius = 0.04 * R;
  // `distance`: the stick's axis from the camera along the line to the planet's centre.
  auto check = [&](double distance, const char* what) {
    SCOPED_TRACE(what);
    const Eigen::Vector3d mid = cam.eye - distance * toCam, a = mid - 3 * R * across,
                          b = mid + 3 * R * across + 0.2 * R * Eigen::Vector3d::UnitZ();
    tracking::ToolShape shape;  // a tiny box at one end, out of view; the stick across it
    shape.boxCentre = a;
    shape.boxHalf = Eigen::Vector3d::Constant(1e-3 * R);
    shape.stickBase = a;
    shape.tip = b;
    shape.baseRadius = shape.tipRadius = radius;
    const auto triangles = tracking::toolTriangles(shape, tracking::Pose{}, 1.0, 48);
    const cv::Mat img =
        renderer.renderAR(background, planet, mesh, cam, {}, std::nullopt, triangles);
    cv::Mat grown, shrunk;
    cv::dilate(planetPixels, grown, cv::Mat::ones(3, 3, CV_8U));
    cv::erode(planetPixels, shrunk, cv::Mat::ones(3, 3, CV_8U));
    int hidden = 0, shown = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const Eigen::Vector3d d =
            (Rt * Eigen::Vector3d((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1)).normalized();
        // The ray's closest approach to the stick's axis, and where it meets the sphere.
        const Eigen::Vector3d u = (b - a).normalized(), w = cam.eye - a;
        const double dd = d.dot(u), den = 1 - dd * dd;
        const double s = (dd * u.dot(w) - d.dot(w)) / den;  // along the ray
        const double gap = (cam.eye + s * d - a - (cam.eye + s * d - a).dot(u) * u).norm();
        const double along = -cam.eye.dot(d), miss = (cam.eye + along * d).norm();
        const double hitSphere = miss < R ? along - std::sqrt(R * R - miss * miss) : 1e300;
        const double pixel = s / cam.fx;  // a pixel's width at the stick (planet metres)
        const cv::Vec3b got = img.at<cv::Vec3b>(y, x), was = bare.at<cv::Vec3b>(y, x);
        if (gap < radius - 1.5 * pixel && s < hitSphere) {
          // On the stick in front: the camera image, wherever the planet was or not.
          EXPECT_EQ(got, camColour) << x << "," << y;
          hidden += shrunk.at<uchar>(y, x) ? 1 : 0;
        } else if (gap > radius + 1.5 * pixel || s > hitSphere + 0.01 * R) {
          // Off the stick, or the stick behind the surface: the picture without the tool.
          if (gap > radius + 1.5 * pixel || shrunk.at<uchar>(y, x)) {
            EXPECT_EQ(got, was) << x << "," << y;
            shown += grown.at<uchar>(y, x) ? 1 : 0;
          }
        }
      }
    return std::make_pair(hidden, shown);
  };
  // In front, between the camera and the planet (2R away from it: its near plane is at R).
  const auto front = check(1.5 * R, "in front");
  EXPECT_GT(front.first, 500);
  EXPECT_GT(front.second, 5000);
  // Nearer the camera than the planet's near plane: clamped, it still hides the planet.
  const auto near = check(0.5 * R, "nearer than the near plane");
  EXPECT_GT(near.first, 500);
  // Behind the planet: it hides nothing of it.
  const auto behind = check(3.5 * R, "behind");
  EXPECT_EQ(behind.first, 0);
  EXPECT_GT(behind.second, 5000);
}

// Issue 9's skips in the renderer, each against doing the work. The views: low over the
// surface looking at the horizon (most of the planet behind it or outside the frustum), a
// close-up off the centre, and the whole planet.
std::vector<terrain::Camera> skipViews(double R, int w, int h) {
  return {terrain::Camera::lookAt({1.05 * R, 0, 0}, {R * 0.94, R * 0.34, 0},
                                  Eigen::Vector3d::UnitZ(), w, h, 50 * M_PI / 180),
          terrain::Camera::lookAt({0.2 * R, -1.3 * R, 0.3 * R}, {0.3 * R, -0.9 * R, 0.2 * R},
                                  Eigen::Vector3d::UnitZ(), w, h, 40 * M_PI / 180),
          orbitCamera(3.0 * R, w, h)};
}

TEST(Skips, CullingDrawsTheSameImageAsTheWholePlanet) {
  SKIP_WITHOUT_GL();
  auto planet = testkit::bumpyTerrain(8, 11, 60000.0);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  int view = 0;
  for (const auto& cam : skipViews(R, 240, 180)) {
    terrain::TessellationSettings ts;
    ts.triangleBudget = 0;
    ts.cull = true;
    terrain::Tessellator culledTess, wholeTess;
    const auto& culled = culledTess.tessellate(planet, cam, ts);
    ts.cull = false;
    const auto& whole = wholeTess.tessellate(planet, cam, ts);
    ASSERT_LT(culled.triangleCount(), whole.triangleCount()) << "view " << view << " culls nothing";
    for (bool wire : {false, true}) {
      render::RenderStyle style;
      style.wireframe = wire;
      const cv::Mat a = renderer.renderAR({}, planet, culled, cam, style);
      const cv::Mat b = renderer.renderAR({}, planet, whole, cam, style);
      EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0)
          << "view " << view << " wireframe " << wire << ": culling changed "
          << cv::countNonZero(cv::Mat(a != b).reshape(1)) << " pixel channels";
      EXPECT_GT(cv::countNonZero(cv::Mat(a).reshape(1)), 0) << "view " << view << " drew nothing";
    }
    ++view;
  }
}

TEST(Skips, SkippedUploadsDrawWhatFreshUploadsDraw) {
  // One renderer that uploads only when the mesh changed, against a new renderer (everything
  // uploaded) every frame, over frames that hold the view, move it and edit the terrain.
  SKIP_WITHOUT_GL();
  auto planet = testkit::bumpyTerrain(7, 12, 8000.0);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer kept;
  terrain::Tessellator tess;
  const auto views = skipViews(R, 200, 150);
  int skipped = 0;
  for (int frame = 0; frame < 9; ++frame) {
    const auto& cam = views[std::size_t(frame / 3)];
    if (frame == 4) {  // an edit under a held view: the mesh changes, the view does not
      std::vector<float> h(planet.heights().begin(), planet.heights().end());
      for (float& x : h) x *= 1.5f;
      planet = terrain::Terrain(planet.chartPtr(), std::move(h));
    }
    const auto& mesh = tess.tessellate(planet, cam, {});
    const cv::Mat a = kept.renderAR({}, planet, mesh, cam, {});
    skipped += !kept.stats().uploadedThisFrame;
    render::PlanetRenderer fresh;
    const cv::Mat b = fresh.renderAR({}, planet, mesh, cam, {});
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "frame " << frame;
  }
  EXPECT_GE(skipped, 4);  // frames 1, 2, 7, 8 held view and terrain
}

TEST(Skips, OverviewEveryFourthFrameIsWhatEveryFrameWouldDraw) {
  // The live app draws the overview every 4th frame: when it does, the image is the one a
  // renderer drawing it every frame shows at that frame (nothing carried over goes stale).
  SKIP_WITHOUT_GL();
  auto planet = testkit::bumpyTerrain(7, 13, 8000.0);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer sometimes, always;
  terrain::Tessellator tess;
  const auto views = skipViews(R, 160, 120);
  for (int frame = 0; frame < 9; ++frame) {
    const auto& cam = views[std::size_t(frame % 3)];
    const auto& mesh = tess.tessellate(planet, cam, {});
    sometimes.renderAR({}, planet, mesh, cam, {});
    always.renderAR({}, planet, mesh, cam, {});
    const cv::Mat every = always.renderOverview(planet, mesh, cam, 120, 120);
    if (frame % 4 != 0) continue;
    const cv::Mat fourth = sometimes.renderOverview(planet, mesh, cam, 120, 120);
    EXPECT_EQ(cv::norm(every, fourth, cv::NORM_INF), 0.0) << "frame " << frame;
  }
}

TEST(Skips, ChangedChunksDrawWhatAWholeUploadDraws) {
  // A local edit under a held view: the renderer sends only the mesh's changed chunks, fewer
  // bytes than the mesh, and draws what a renderer sent the whole mesh draws.
  SKIP_WITHOUT_GL();
  auto planet = testkit::bumpyTerrain(9, 14, 8000.0);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer partial, whole;
  whole.setPartialUploads(false);
  const auto cam = orbitCamera(1.8 * R, 480, 360);
  terrain::TessellationSettings ts;
  ts.distMaxPx = 0.25;
  terrain::Tessellator tess;
  partial.renderAR({}, planet, tess.tessellate(planet, cam, ts), cam, {});
  whole.renderAR({}, planet, tess.mesh(), cam, {});
  // Bumps 2 % of the radius across beside the visible disc's centre: a 5 m one changes
  // heights but no split (only the chunks holding its vertices are sent), a 20 km one changes
  // the tessellation (its triangles shift everything after them in the bintree's order).
  const Eigen::Vector3d towardCamera = cam.eye.normalized();
  const Eigen::Vector3d spot =
      R * (towardCamera + 0.4 * towardCamera.unitOrthogonal()).normalized();
  edit::EditPipeline pipe(planet);
  for (double strength : {5.0, 20000.0}) {
    edit::BrushSettings b;
    b.radius = 0.02 * R;
    b.strength = strength;
    pipe.apply(edit::GaussianBrush(b), {spot, 0.0});
    const auto& mesh = tess.tessellate(planet, cam, ts);
    const cv::Mat a = partial.renderAR({}, planet, mesh, cam, {});
    const cv::Mat c = whole.renderAR({}, planet, mesh, cam, {});
    EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0.0) << strength;
    EXPECT_EQ(whole.stats().uploadedBytes, whole.stats().meshBytes);
    EXPECT_GT(partial.stats().uploadedBytes, 0u) << strength;
    EXPECT_LE(partial.stats().uploadedBytes, partial.stats().meshBytes) << strength;
    if (strength < 10) {
      EXPECT_LT(partial.stats().uploadedBytes, partial.stats().meshBytes / 4)
          << partial.stats().uploadedBytes << " of " << partial.stats().meshBytes << " bytes";
    }
    std::printf("[ info ] %g m bump: %zu of %zu bytes sent (%zu triangles)\n", strength,
                partial.stats().uploadedBytes, partial.stats().meshBytes, mesh.triangleCount());
  }
}

TEST(RenderUploads, ChangedRangesCoverEveryChangedByteAndNothingElseOfWholeChunks) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t chunk = 1 + rng() % 64;
    std::vector<std::uint8_t> a(rng() % 600), b;
    for (auto& x : a) x = std::uint8_t(rng());
    b = a;
    b.resize(rng() % 600, 7);
    for (int k = int(rng() % 5); k > 0 && !b.empty(); --k) b[rng() % b.size()] ^= 0x5a;
    const auto ranges = render::changedRanges(a, b, chunk);
    std::vector<std::uint8_t> covered(b.size(), 0);
    std::size_t end = 0;
    for (const auto& r : ranges) {
      ASSERT_GE(r.offset, end) << "ranges overlap or are out of order";
      ASSERT_EQ(r.offset % chunk, 0u);
      ASSERT_LE(r.offset + r.size, b.size());
      ASSERT_TRUE(r.offset > end || end == 0 || r.offset == 0) << "adjacent ranges not merged";
      for (std::size_t i = r.offset; i < r.offset + r.size; ++i) covered[i] = 1;
      end = r.offset + r.size;
    }
    // Applying the ranges to a copy of `a` gives `b`; every uncovered chunk was unchanged.
    std::vector<std::uint8_t> c = a;
    c.resize(b.size());
    for (const auto& r : ranges)
      std::copy_n(b.begin() + long(r.offset), r.size, c.begin() + long(r.offset));
    ASSERT_EQ(c, b) << "trial " << trial;
    for (std::size_t at = 0; at < b.size(); at += chunk) {
      if (covered[at]) continue;
      ASSERT_LE(at + std::min(chunk, b.size() - at), a.size());
      ASSERT_TRUE(std::equal(b.begin() + long(at), b.begin() + long(std::min(b.size(), at + chunk)),
                             a.begin() + long(at)))
          << "an unchanged chunk was sent";
    }
  }
}
