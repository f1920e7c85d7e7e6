// The renderer in the AR app's frame, on headless OpenGL (skipped with a message where EGL is
// missing): the planet anchored on the detected marker, the cursor and the force arrow, the
// tool's depth pass hiding the planet where it is in front, and the work skipped from frame to
// frame (culling, uploads, the overview's rate, changed chunks), each skip against doing the
// work. The picture itself against a sphere's known facts is test_render.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "gl_test.hpp"
#include "render/changed_ranges.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "terrain/tessellator.hpp"
#include "test_render_util.hpp"
#include "test_terrains.hpp"
#include "tracking/detector.hpp"
#include "tracking/pose.hpp"
#include "tracking/synth.hpp"
#include "tracking/tool_shape.hpp"
#include "tracking/tracker.hpp"

using namespace ps;
using namespace ps::rendertest;

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
  SmoothScene scene(7);
  const core::Chart* chart = &scene.planet.chart();
  const auto& mesh = scene.tess.tessellate(scene.planet, scene.cam, {});
  // The vertex facing the camera most directly.
  const int side = chart->grid().side();
  core::GridPoint best;
  double bestDot = -2;
  for (int v = 1; v < side - 1; v += 4)
    for (int u = 0; u < side - 1; u += 4) {
      const double d = chart->up(u, v).dot(scene.cam.eye.normalized());
      if (d > bestDot) bestDot = d, best = {u, v};
    }
  render::Cursor c{best, 0.2 * scene.R};
  const Eigen::Vector3d n = chart->up(best.u, best.v);
  c.arrowFrom = scene.R * n;
  c.arrow = 0.5 * scene.R * n.cross(Eigen::Vector3d::UnitZ()).normalized();  // across the view
  const cv::Mat img = scene.renderer.renderAR({}, scene.planet, mesh, scene.cam, {}, c);
  cv::Mat ring, arrow;
  cv::inRange(img, cv::Scalar(0, 200, 240), cv::Scalar(60, 240, 255), ring);   // (1, .85, .1)
  cv::inRange(img, cv::Scalar(50, 240, 30), cv::Scalar(100, 255, 80), arrow);  // (.2, 1, .3)
  EXPECT_GT(cv::countNonZero(ring), 100);
  EXPECT_GT(cv::countNonZero(arrow), 40);
  // Without an arrow, no arrow colour anywhere.
  c.arrow.setZero();
  const cv::Mat none = scene.renderer.renderAR({}, scene.planet, mesh, scene.cam, {}, c);
  cv::inRange(none, cv::Scalar(50, 240, 30), cv::Scalar(100, 255, 80), arrow);
  EXPECT_EQ(cv::countNonZero(arrow), 0);
}

// The tool's depth pass (render/occluder_pass.hpp): a stick of known radius across the view in
// front of a planet of known radius hides the planet exactly where a ray meets the stick first
// (the camera image shows there, pixel for pixel), and nowhere else; the same stick behind the
// planet, or nearer the camera than the planet's near plane, is judged the same way.
TEST(RenderGl, TheToolHidesThePlanetExactlyWhereItIsInFront) {
  SKIP_WITHOUT_GL();
  SmoothScene scene(7);
  terrain::TessellationSettings ts;
  ts.distMaxPx = 0.5;
  const auto& mesh = scene.tess.tessellate(scene.planet, scene.cam, ts);
  const cv::Vec3b camColour(255, 0, 255);  // the "camera image": no planet pixel has it
  const cv::Mat background(scene.cam.height, scene.cam.width, CV_8UC3, cv::Scalar(camColour));
  const cv::Mat bare = scene.renderer.renderAR(background, scene.planet, mesh, scene.cam, {});
  cv::Mat planetPixels;
  cv::inRange(bare, cv::Scalar(camColour), cv::Scalar(camColour), planetPixels);
  planetPixels = ~planetPixels;
  ASSERT_GT(cv::countNonZero(planetPixels), 5000);
  const Eigen::Vector3d toCam = scene.cam.eye.normalized();
  const Eigen::Vector3d across = toCam.cross(Eigen::Vector3d::UnitZ()).normalized();
  const double radius = 0.04 * scene.R;
  // `distance`: the stick's axis from the camera along the line to the planet's centre.
  auto check = [&](double distance, const char* what) {
    SCOPED_TRACE(what);
    const Eigen::Vector3d mid = scene.cam.eye - distance * toCam, a = mid - 3 * scene.R * across,
                          b = mid + 3 * scene.R * across + 0.2 * scene.R * Eigen::Vector3d::UnitZ();
    tracking::ToolShape shape;  // a tiny box at one end, out of view; the stick across it
    shape.boxCentre = a;
    shape.boxHalf = Eigen::Vector3d::Constant(1e-3 * scene.R);
    shape.stickBase = a;
    shape.tip = b;
    shape.baseRadius = shape.tipRadius = radius;
    const auto triangles = tracking::toolTriangles(shape, tracking::Pose{}, 1.0, 48);
    const cv::Mat img = scene.renderer.renderAR(background, scene.planet, mesh, scene.cam, {},
                                                std::nullopt, triangles);
    cv::Mat grown, shrunk;
    cv::dilate(planetPixels, grown, cv::Mat::ones(3, 3, CV_8U));
    cv::erode(planetPixels, shrunk, cv::Mat::ones(3, 3, CV_8U));
    int hidden = 0, shown = 0;
    for (int y = 0; y < scene.cam.height; ++y)
      for (int x = 0; x < scene.cam.width; ++x) {
        const Eigen::Vector3d d = pixelRay(scene.cam, x, y);
        // The ray's closest approach to the stick's axis, and where it meets the sphere.
        const Eigen::Vector3d u = (b - a).normalized(), w = scene.cam.eye - a;
        const double dd = d.dot(u), den = 1 - dd * dd;
        const double s = (dd * u.dot(w) - d.dot(w)) / den;  // along the ray
        const double gap =
            (scene.cam.eye + s * d - a - (scene.cam.eye + s * d - a).dot(u) * u).norm();
        const double along = -scene.cam.eye.dot(d), miss = (scene.cam.eye + along * d).norm();
        const double hitSphere =
            miss < scene.R ? along - std::sqrt(scene.R * scene.R - miss * miss) : 1e300;
        const double pixel = s / scene.cam.fx;  // a pixel's width at the stick (planet metres)
        const cv::Vec3b got = img.at<cv::Vec3b>(y, x), was = bare.at<cv::Vec3b>(y, x);
        if (gap < radius - 1.5 * pixel && s < hitSphere) {
          // On the stick in front: the camera image, wherever the planet was or not.
          EXPECT_EQ(got, camColour) << x << "," << y;
          hidden += shrunk.at<uchar>(y, x) ? 1 : 0;
        } else if (gap > radius + 1.5 * pixel || s > hitSphere + 0.01 * scene.R) {
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
  const auto front = check(1.5 * scene.R, "in front");
  EXPECT_GT(front.first, 500);
  EXPECT_GT(front.second, 5000);
  // Nearer the camera than the planet's near plane: clamped, it still hides the planet.
  const auto near = check(0.5 * scene.R, "nearer than the near plane");
  EXPECT_GT(near.first, 500);
  // Behind the planet: it hides nothing of it.
  const auto behind = check(3.5 * scene.R, "behind");
  EXPECT_EQ(behind.first, 0);
  EXPECT_GT(behind.second, 5000);
}

// Issue 9's skips in the renderer, each against doing the work. The views: low over the
// surface looking at the horizon (most of the planet behind it or outside the frustum), a
// close-up off the centre, and the whole planet.
namespace {
std::vector<terrain::Camera> skipViews(double R, int w, int h) {
  return {terrain::Camera::lookAt({1.05 * R, 0, 0}, {R * 0.94, R * 0.34, 0},
                                  Eigen::Vector3d::UnitZ(), w, h, 50 * M_PI / 180),
          terrain::Camera::lookAt({0.2 * R, -1.3 * R, 0.3 * R}, {0.3 * R, -0.9 * R, 0.2 * R},
                                  Eigen::Vector3d::UnitZ(), w, h, 40 * M_PI / 180),
          orbitCamera(3.0 * R, w, h)};
}
}  // namespace

TEST(Skips, CullingDrawsTheSameImageAsTheWholePlanet) {
  SKIP_WITHOUT_GL();
  BumpyScene scene(8, 11, 60000.0);
  render::PlanetRenderer renderer;
  int view = 0;
  for (const auto& cam : skipViews(scene.R, 240, 180)) {
    terrain::TessellationSettings ts;
    ts.triangleBudget = 0;
    ts.cull = true;
    terrain::Tessellator culledTess, wholeTess;
    const auto& culled = culledTess.tessellate(scene.planet, cam, ts);
    ts.cull = false;
    const auto& whole = wholeTess.tessellate(scene.planet, cam, ts);
    ASSERT_LT(culled.triangleCount(), whole.triangleCount()) << "view " << view << " culls nothing";
    for (bool wire : {false, true}) {
      render::RenderStyle style;
      style.wireframe = wire;
      const cv::Mat a = renderer.renderAR({}, scene.planet, culled, cam, style);
      const cv::Mat b = renderer.renderAR({}, scene.planet, whole, cam, style);
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
  BumpyScene scene(7, 12, 8000.0);
  render::PlanetRenderer kept;
  terrain::Tessellator tess;
  const auto views = skipViews(scene.R, 200, 150);
  int skipped = 0;
  for (int frame = 0; frame < 9; ++frame) {
    const auto& cam = views[std::size_t(frame / 3)];
    if (frame == 4) {  // an edit under a held view: the mesh changes, the view does not
      std::vector<float> h(scene.planet.heights().begin(), scene.planet.heights().end());
      for (float& x : h) x *= 1.5f;
      scene.planet = terrain::Terrain(scene.planet.chartPtr(), std::move(h));
    }
    const auto& mesh = tess.tessellate(scene.planet, cam, {});
    const cv::Mat a = kept.renderAR({}, scene.planet, mesh, cam, {});
    skipped += !kept.stats().uploadedThisFrame;
    render::PlanetRenderer fresh;
    const cv::Mat b = fresh.renderAR({}, scene.planet, mesh, cam, {});
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "frame " << frame;
  }
  EXPECT_GE(skipped, 4);  // frames 1, 2, 7, 8 held view and terrain
}

TEST(Skips, OverviewEveryFourthFrameIsWhatEveryFrameWouldDraw) {
  // The live app draws the overview every 4th frame: when it does, the image is the one a
  // renderer drawing it every frame shows at that frame (nothing carried over goes stale).
  SKIP_WITHOUT_GL();
  BumpyScene scene(7, 13, 8000.0);
  render::PlanetRenderer sometimes, always;
  terrain::Tessellator tess;
  const auto views = skipViews(scene.R, 160, 120);
  for (int frame = 0; frame < 9; ++frame) {
    const auto& cam = views[std::size_t(frame % 3)];
    const auto& mesh = tess.tessellate(scene.planet, cam, {});
    sometimes.renderAR({}, scene.planet, mesh, cam, {});
    always.renderAR({}, scene.planet, mesh, cam, {});
    const cv::Mat every = always.renderOverview(scene.planet, mesh, cam, 120, 120);
    if (frame % 4 != 0) continue;
    const cv::Mat fourth = sometimes.renderOverview(scene.planet, mesh, cam, 120, 120);
    EXPECT_EQ(cv::norm(every, fourth, cv::NORM_INF), 0.0) << "frame " << frame;
  }
}

TEST(Skips, ChangedChunksDrawWhatAWholeUploadDraws) {
  // A local edit under a held view: the renderer sends only the mesh's changed chunks, fewer
  // bytes than the mesh, and draws what a renderer sent the whole mesh draws.
  SKIP_WITHOUT_GL();
  BumpyScene scene(9, 14, 8000.0);
  render::PlanetRenderer partial, whole;
  whole.setPartialUploads(false);
  const auto cam = orbitCamera(1.8 * scene.R, 480, 360);
  terrain::TessellationSettings ts;
  ts.distMaxPx = 0.25;
  terrain::Tessellator tess;
  partial.renderAR({}, scene.planet, tess.tessellate(scene.planet, cam, ts), cam, {});
  whole.renderAR({}, scene.planet, tess.mesh(), cam, {});
  // Bumps 2 % of the radius across beside the visible disc's centre: a 5 m one changes
  // heights but no split (only the chunks holding its vertices are sent), a 20 km one changes
  // the tessellation (its triangles shift everything after them in the bintree's order).
  const Eigen::Vector3d towardCamera = cam.eye.normalized();
  const Eigen::Vector3d spot =
      scene.R * (towardCamera + 0.4 * towardCamera.unitOrthogonal()).normalized();
  edit::EditPipeline pipe(scene.planet);
  for (double strength : {5.0, 20000.0}) {
    edit::BrushSettings b;
    b.radius = 0.02 * scene.R;
    b.strength = strength;
    pipe.apply(edit::GaussianBrush(b), {spot, 0.0});
    const auto& mesh = tess.tessellate(scene.planet, cam, ts);
    const cv::Mat a = partial.renderAR({}, scene.planet, mesh, cam, {});
    const cv::Mat c = whole.renderAR({}, scene.planet, mesh, cam, {});
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
