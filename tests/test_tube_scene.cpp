// The torus and the cylinder in the AR scene (issue 28): the tool tip's height above their
// surface and its control vertex (edit/surface_height.hpp, edit::nearestVertex) against brute
// force over every vertex, the scene's scale from the bounding sphere (replay::FrameStepper),
// and the default planet's dimensions and their refusals (app/default_planet.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <string>

#include "app/default_planet.hpp"
#include "core/chart_factory.hpp"
#include "core/cylinder_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/torus_chart.hpp"
#include "edit/control_vertex.hpp"
#include "edit/surface_height.hpp"
#include "gl_test.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "replay/replay.hpp"
#include "replay/session_timeline.hpp"
#include "short_scene.hpp"
#include "terrain/relief.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/video.hpp"

using namespace ps;

namespace {

constexpr double kTorusMajor = 4.5e6, kTorusMinor = 1.8e6;          // the torus
constexpr double kCylinderRadius = 6.0e6, kCylinderLength = 4.0e6;  // the cylinder

terrain::Terrain withRelief(std::shared_ptr<const core::Chart> chart) {
  terrain::ReliefParams params;
  params.seed = 7;
  auto h = terrain::generateRelief(*chart, params);
  return terrain::Terrain(std::move(chart), std::move(h));
}

struct Tube {
  const char* name;
  std::shared_ptr<const core::Chart> chart;
};
std::vector<Tube> tubes(int n) {
  return {
      {"torus", std::make_shared<core::TorusChart>(core::GridSize(n), kTorusMajor, kTorusMinor)},
      {"cylinder",
       std::make_shared<core::CylinderChart>(core::GridSize(n), kCylinderRadius, kCylinderLength)}};
}

// The largest distance between neighbouring grid vertices at height 0 (a cell's side).
double largestSpacing(const core::Chart& c) {
  const int m = c.grid().m();
  double s = 0;
  for (int v = 0; v <= m; ++v)
    for (int u = 0; u <= m; ++u) {
      if (u < m) s = std::max(s, (c.position(u + 1, v, 0) - c.position(u, v, 0)).norm());
      if (v < m) s = std::max(s, (c.position(u, v + 1, 0) - c.position(u, v, 0)).norm());
    }
  return s;
}

}  // namespace

// A point straight above (or below) a vertex by d along its normal is d above the sculpted
// surface there, and its control vertex is that vertex (its canonical twin on a seam): every
// vertex of a 65^2 grid, 5 offsets each, heights from the procedural relief.
TEST(TubeScene, HeightAlongTheNormalIsTheOffsetAtEveryVertex) {
  for (const auto& tube : tubes(6)) {
    SCOPED_TRACE(tube.name);
    const terrain::Terrain t = withRelief(tube.chart);
    const core::Chart& c = t.chart();
    const int m = c.grid().m();
    const double limit = c.heightLimit();
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u)
        for (double f : {-0.9, -0.3, 0.0, 0.4, 0.9}) {
          const double d = f * limit;
          const auto got = edit::surfaceContact(t, c.position(u, v, t.height(u, v) + d));
          ASSERT_TRUE(got.has_value()) << u << "," << v;
          EXPECT_EQ(got->control, c.canonical(u, v)) << u << "," << v << " d " << d;
          ASSERT_NEAR(got->height, d, 1e-5) << u << "," << v;
        }
  }
}

// The control vertex of points anywhere near the surface (up to a quarter of the tube's radius
// above or below it) is the vertex nearest on the surface at height 0, found by a scan of every
// vertex; the height it reports is within a cell of the distance to the nearest sculpted
// vertex, with the sign of the side the point is on.
TEST(TubeScene, ControlVertexAndHeightAgreeWithBruteForce) {
  std::mt19937 rng(28);
  for (const auto& tube : tubes(6)) {
    SCOPED_TRACE(tube.name);
    const terrain::Terrain t = withRelief(tube.chart);
    const core::Chart& c = t.chart();
    const int m = c.grid().m();
    const double spacing = largestSpacing(c);
    std::uniform_real_distribution<double> along(0.0, double(m)), off(-1.0, 1.0);
    for (int k = 0; k < 400; ++k) {
      const double gu = along(rng), gv = along(rng);
      // Clear of the relief (8 km at most) so that the side is certain.
      const double d = off(rng) * c.heightLimit();
      if (std::abs(d) < 2e4) continue;
      const Eigen::Vector3d p = c.positionAt(gu, gv, d);
      const auto got = edit::surfaceContact(t, p);
      ASSERT_TRUE(got.has_value());
      core::GridPoint best{-1, -1};
      double bestD2 = std::numeric_limits<double>::infinity(), nearest = bestD2;
      for (int v = 0; v <= m; ++v)
        for (int u = 0; u <= m; ++u) {
          const double d2 = (c.position(u, v, 0.0) - p).squaredNorm();
          if (d2 < bestD2 * (1 - 1e-12)) bestD2 = d2, best = c.canonical(u, v);
          nearest = std::min(nearest, (c.position(u, v, t.height(u, v)) - p).norm());
        }
      EXPECT_EQ(got->control, best) << "point " << k << " at (" << gu << ", " << gv << ")";
      EXPECT_EQ(got->height > 0, d > 0) << "point " << k;
      EXPECT_LE(std::abs(std::abs(got->height) - nearest), 0.75 * spacing) << "point " << k;
    }
  }
}

// Beyond the cylinder's open ends only the rims are surface: the height there is the distance
// to the rim circle, so a tip over the opening does not touch; on the axis there is no contact,
// nor on the torus's axis and centre circle.
TEST(TubeScene, CylinderEndsAndDegeneratePoints) {
  const auto chart =
      std::make_shared<core::CylinderChart>(core::GridSize(6), kCylinderRadius, kCylinderLength);
  const terrain::Terrain t = withRelief(chart);
  const int m = chart->grid().m();
  for (int u = 0; u < m; u += 7) {
    const Eigen::Vector3d rim = chart->position(u, m, t.height(u, m));
    const auto above = edit::surfaceContact(t, rim + Eigen::Vector3d(0, 0, 5e3));
    ASSERT_TRUE(above.has_value());
    EXPECT_NEAR(above->height, 5e3, 1e-3);
    EXPECT_EQ(above->control, (core::GridPoint{u, m}));
    // Over the opening, half way to the axis, just above the end: far from any surface.
    const auto inside =
        edit::surfaceContact(t, 0.5 * rim + Eigen::Vector3d(0, 0, 0.5 * rim.z() + 1e3));
    ASSERT_TRUE(inside.has_value());
    EXPECT_GT(inside->height, 0.4 * kCylinderRadius);
  }
  EXPECT_FALSE(edit::surfaceContact(t, {0, 0, 1e5}).has_value());
  const auto torus =
      std::make_shared<core::TorusChart>(core::GridSize(6), kTorusMajor, kTorusMinor);
  const terrain::Terrain tt = withRelief(torus);
  EXPECT_FALSE(edit::surfaceContact(tt, {0, 0, 3e5}).has_value());          // the axis
  EXPECT_FALSE(edit::surfaceContact(tt, {kTorusMajor, 0, 0}).has_value());  // the centre circle
  EXPECT_FALSE(edit::surfaceContact(tt, {NAN, 0, 0}).has_value());
}

// The displayed planet's radius stands for the bounding sphere: a sphere's own radius (the
// same double, so lat-long replays keep their bits), a torus's R + r, a cylinder's
// hypot(radius, length / 2). Every frame's tip height is the surface contact's, scaled.
TEST(TubeScene, StepperScalesByTheBoundingSphereAndMeasuresTheTipsHeight) {
  const auto ll = std::make_shared<core::LatLongChart>(core::GridSize(6), 6372790.0);
  EXPECT_EQ(core::boundingRadius(*ll), ll->sphereRadius());
  for (const auto& tube : tubes(7)) {
    SCOPED_TRACE(tube.name);
    terrain::Terrain t = withRelief(tube.chart);
    const double bound = core::boundingRadius(t.chart());
    EXPECT_DOUBLE_EQ(bound, tube.chart->name() == std::string("torus")
                                ? kTorusMajor + kTorusMinor
                                : std::hypot(kCylinderRadius, 0.5 * kCylinderLength));
    tracking::FrameSource src(testkit::shortSceneVideo());
    const auto options = testkit::shortSceneOptions();
    replay::FrameStepper stepper(testkit::shortSceneCamera().forImageSize(src.size()), t, options);
    EXPECT_EQ(stepper.scale(), bound / options.scene.planetRadius);
    cv::Mat image;
    int tips = 0;
    while (src.read(image)) {
      const auto r = stepper.step(image, src.index(), src.index() / src.fps());
      if (!r.scene.tipValid) continue;
      ++tips;
      const Eigen::Vector3d p = r.scene.tipPlanet * stepper.scale();
      const auto c = edit::surfaceContact(t, p);
      ASSERT_TRUE(c.has_value());
      EXPECT_NEAR(r.scene.tipHeight, c->height / stepper.scale(), 1e-12);
      EXPECT_EQ(r.touching, r.scene.tipHeight <= options.scene.touchDistance);
      if (r.touching) {
        EXPECT_EQ(r.control, c->control);
      }
    }
    EXPECT_GT(tips, 0);
  }
}

// Defaults when the user gives none, and impossible dimensions refused naming the option.
TEST(TubeScene, DefaultDimensionsAndRefusals) {
  using core::ChartShape;
  const core::ChartDims torus = app::resolveDims(ChartShape::kTorus, {});
  EXPECT_EQ(torus.radius, app::kDefaultTorusMajorMetres);
  EXPECT_EQ(torus.minorRadius, app::kDefaultTorusMinorMetres);
  const core::ChartDims tube = app::resolveDims(ChartShape::kCylinder, {});
  EXPECT_EQ(tube.radius, app::kDefaultCylinderRadiusMetres);
  EXPECT_EQ(tube.length, app::kDefaultCylinderLengthMetres);
  EXPECT_EQ(app::resolveDims(ChartShape::kLatLong, {}).radius, app::kDefaultRadiusMetres);
  const core::ChartDims given = app::resolveDims(ChartShape::kTorus, {3e6, 1e6, std::nullopt});
  EXPECT_EQ(given.radius, 3e6);
  EXPECT_EQ(given.minorRadius, 1e6);
  auto refused = [](ChartShape s, const app::PlanetDims& d) -> std::string {
    try {
      (void)app::resolveDims(s, d);
    } catch (const core::InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string big = refused(ChartShape::kTorus, {3e6, 3e6, std::nullopt});
  EXPECT_NE(big.find("--minor-radius"), std::string::npos) << big;
  EXPECT_NE(big.find("--radius"), std::string::npos) << big;
  // Only --radius typed, below the default tube: the message says what the default is.
  const std::string small = refused(ChartShape::kTorus, {1e6, std::nullopt, std::nullopt});
  EXPECT_NE(small.find("--minor-radius defaults to"), std::string::npos) << small;
  for (double bad : {0.0, -5.0, double(NAN), double(INFINITY)}) {
    const std::string len = refused(ChartShape::kCylinder, {std::nullopt, std::nullopt, bad});
    EXPECT_NE(len.find("--length"), std::string::npos) << len;
    const std::string rad = refused(ChartShape::kCylinder, {bad, std::nullopt, std::nullopt});
    EXPECT_NE(rad.find("--radius"), std::string::npos) << rad;
  }
  EXPECT_NE(refused(ChartShape::kLatLong, {std::nullopt, 1e6, std::nullopt}).find("--minor-radius"),
            std::string::npos);
  EXPECT_NE(refused(ChartShape::kTorus, {std::nullopt, std::nullopt, 1e6}).find("--length"),
            std::string::npos);
  EXPECT_NE(refused(ChartShape::kFlat, {}).find("--chart flat"), std::string::npos);
}

// The overview and the cursor on a torus and a cylinder (headless GL; skipped without it): the
// overview stands back from the bounding sphere (it once refused every planet without a
// radius) and shows the planet and the AR camera's frustum; the AR view's cursor (a ring laid
// onto the surface about the control vertex) changes pixels round the control vertex only.
TEST(TubeScene, OverviewAndCursorDrawTorusAndCylinder) {
  SKIP_WITHOUT_GL();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  for (const auto& tube : tubes(8)) {
    SCOPED_TRACE(tube.name);
    const terrain::Terrain t = withRelief(tube.chart);
    const double bound = core::boundingRadius(t.chart());
    const terrain::Camera cam = terrain::Camera::lookAt(
        3.0 * bound * Eigen::Vector3d(-0.8, -0.5, 0.25).normalized(), Eigen::Vector3d::Zero(),
        Eigen::Vector3d::UnitZ(), 320, 240, 50 * M_PI / 180);
    terrain::Tessellator tess;
    terrain::TessellationSettings ts;
    ts.distMaxPx = 2;
    const terrain::Mesh& mesh = tess.tessellate(t, cam, ts);
    const cv::Mat over = renderer.renderOverview(t, mesh, cam, 240, 240);
    if (std::getenv("PS_DUMP")) cv::imwrite(std::string("/tmp/x/over_") + tube.name + ".png", over);
    int lit = 0, yellow = 0;
    for (int y = 0; y < over.rows; ++y)
      for (int x = 0; x < over.cols; ++x) {
        const cv::Vec3b c = over.at<cv::Vec3b>(y, x);  // BGR; background (20, 10, 8)
        lit += std::abs(int(c[0]) - 20) + std::abs(int(c[1]) - 10) + std::abs(int(c[2]) - 8) > 30;
        yellow += c[2] > 200 && c[1] > 150 && c[0] < 90;
      }
    EXPECT_GT(lit, 800) << "planet pixels in the overview";
    EXPECT_GT(yellow, 50) << "frustum pixels in the overview";

    // The cursor about the vertex facing the camera.
    const int m = t.grid().m();
    const core::GridPoint control{m / 2 + m / 8, m / 8};
    render::RenderStyle style;
    style.boardShadow = style.atmosphere = false;
    const cv::Mat plain = renderer.renderAR({}, t, mesh, cam, style, std::nullopt);
    const double r = 0.1 * bound;
    const cv::Mat withCursor =
        renderer.renderAR({}, t, mesh, cam, style, render::Cursor{control, r});
    const Eigen::Vector3d centre = t.chart().position(control.u, control.v, 0);
    if (std::getenv("PS_DUMP")) {
      cv::imwrite(std::string("/tmp/x/ar_") + tube.name + ".png", plain);
      cv::imwrite(std::string("/tmp/x/arc_") + tube.name + ".png", withCursor);
    }
    int changed = 0, far = 0;
    for (int y = 0; y < plain.rows; ++y)
      for (int x = 0; x < plain.cols; ++x) {
        if (plain.at<cv::Vec3b>(y, x) == withCursor.at<cv::Vec3b>(y, x)) continue;
        ++changed;
        // Every changed pixel lies within the ring's reach of the control vertex on screen.
        const Eigen::Vector2d at = cam.project(cam.toCamera(centre));
        const double reachPx = cam.fx * 1.5 * r / (cam.eye - centre).norm();
        far += (Eigen::Vector2d(x, y) - at).norm() > reachPx + 3;
      }
    EXPECT_GT(changed, 60) << "the cursor drew nothing";
    EXPECT_EQ(far, 0) << "cursor pixels away from the control vertex";
  }
}

// A live recording's sidecar keeps a torus's minor radius and a cylinder's length (a sphere's
// header has neither key, as before), reads them back, and a planet of other dimensions is
// refused as another start planet.
TEST(TubeScene, SessionSidecarsKeepTheDimensions) {
  const auto dir = testkit::shortSceneDir();
  const auto calib = testkit::shortSceneCamera();
  const auto options = testkit::shortSceneOptions();
  auto sidecarOf = [&](const terrain::Terrain& t, const std::string& name) {
    const auto path = dir / (name + ".session.jsonl");
    replay::TimelineWriter w;
    w.open(path,
           replay::SessionStart::of(t, "", int(t.grid().side()), 7, calib, "synthetic", options, 30,
                                    0),
           replay::SessionSettings::of(options));
    w.close();
    return path;
  };
  const terrain::Terrain sphere =
      withRelief(std::make_shared<core::LatLongChart>(core::GridSize(5), 6372790.0));
  const auto sphereHeader =
      replay::toJson(replay::readSessionTimeline(sidecarOf(sphere, "s")).start);
  EXPECT_FALSE(sphereHeader["planet"].contains("minor_radius_m"));
  EXPECT_FALSE(sphereHeader["planet"].contains("length_m"));
  for (const auto& tube : tubes(5)) {
    SCOPED_TRACE(tube.name);
    const terrain::Terrain t = withRelief(tube.chart);
    const replay::SessionTimeline tl = replay::readSessionTimeline(sidecarOf(t, tube.name));
    const core::ChartDims dims = core::dimsOf(t.chart());
    EXPECT_EQ(tl.start.radius, dims.radius);
    EXPECT_EQ(tl.start.minorRadius, dims.minorRadius);
    EXPECT_EQ(tl.start.length, dims.length);
    EXPECT_NO_THROW(replay::checkSessionStart(tl, t, calib));
    // The same shape with the other dimension changed: another planet.
    core::ChartDims other = dims;
    (other.minorRadius > 0 ? other.minorRadius : other.length) *= 0.5;
    const terrain::Terrain different(core::makeChart(core::shapeOf(t.chart()), t.grid(), other),
                                     std::vector<float>(t.heights().begin(), t.heights().end()));
    EXPECT_THROW(replay::checkSessionStart(tl, different, calib), core::InputError);
  }
}
