// The AR view's board shadow and atmosphere rim (render/atmosphere_passes.hpp) on headless
// OpenGL (skipped with a message where EGL is missing), against where they must fall by the
// geometry: off by default changes nothing; the shadow darkens the board away from the sun and
// nowhere else, and not at all with the sun below the board; the rim brightens a thin band
// outside the silhouette and leaves the planet and the far background alone. And the `--sun`
// option's parsing (render/sun.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <string>

#include "core/input_error.hpp"
#include "gl_test.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/sun.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

const cv::Scalar kGrey(128, 128, 128);

cv::Mat draw(render::PlanetRenderer& r, const terrain::Terrain& planet, const terrain::Camera& cam,
             const render::RenderStyle& style) {
  terrain::Tessellator tess;
  const cv::Mat background(cam.height, cam.width, CV_8UC3, kGrey);
  return r.renderAR(background, planet, tess.tessellate(planet, cam, {}), cam, style);
}

// The distance from the origin to the line through `from` along unit `dir`, where the closest
// point lies ahead (t > 0); infinity otherwise.
double rayDistance(const Eigen::Vector3d& from, const Eigen::Vector3d& dir) {
  const double t = -from.dot(dir);
  return t > 0 ? (from + t * dir).norm() : INFINITY;
}

cv::Vec3b at(const cv::Mat& image, const Eigen::Vector2d& px) {
  return image.at<cv::Vec3b>(int(std::lround(px.y())), int(std::lround(px.x())));
}

bool inside(const terrain::Camera& cam, const Eigen::Vector2d& px) {
  return px.x() >= 2 && px.y() >= 2 && px.x() <= cam.width - 3 && px.y() <= cam.height - 3;
}

}  // namespace

// With both flags off, a renderer that drew the shadow and the rim before draws the very image
// a fresh one does (the passes leave no state behind), and so does a flag whose pass has
// nothing to draw (the sun below the board).
TEST(RenderAtmosphere, OffChangesNothing) {
  SKIP_WITHOUT_GL();
  const auto planet = testkit::levelTerrain(8);
  const double R = planet.chart().sphereRadius();
  render::EglContext gl;
  const auto cam =
      terrain::Camera::lookAt(R * Eigen::Vector3d(4, 1.5, 2.5), Eigen::Vector3d::Zero(),
                              Eigen::Vector3d::UnitZ(), 320, 240, 50 * M_PI / 180);
  render::PlanetRenderer fresh;
  const cv::Mat reference = draw(fresh, planet, cam, {});
  render::PlanetRenderer used;
  render::RenderStyle on;
  on.boardShadow = on.atmosphere = true;
  const cv::Mat withBoth = draw(used, planet, cam, on);
  EXPECT_GT(cv::norm(withBoth, reference, cv::NORM_L1), 0.0);
  EXPECT_EQ(cv::norm(draw(used, planet, cam, {}), reference, cv::NORM_INF), 0.0);
  render::RenderStyle below;
  below.sun = render::sunDirection({30, -10});
  const cv::Mat belowOff = draw(fresh, planet, cam, below);
  below.boardShadow = true;
  EXPECT_EQ(cv::norm(draw(used, planet, cam, below), belowOff, cv::NORM_INF), 0.0);
}

// Sun at azimuth 45, elevation 35.26 (the default): the board point 1.6 R from the contact
// point, away from the sun, lies in the full shadow (its ray toward the sun passes well inside
// the sphere) and comes out about half as bright; a board point 2.5 R toward the sun keeps its
// grey exactly; with the sun below the board the image is the one without the shadow.
TEST(RenderAtmosphere, TheBoardShadowFallsAwayFromTheSun) {
  SKIP_WITHOUT_GL();
  const auto planet = testkit::levelTerrain(8);
  const double R = planet.chart().sphereRadius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  const Eigen::Vector3d sun = render::sunDirection({});
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d away = -Eigen::Vector3d(sun.x(), sun.y(), 0).normalized();
  const Eigen::Vector3d across = up.cross(away);
  const auto cam =
      terrain::Camera::lookAt(R * (6 * across + 0.8 * away + 4 * up), R * (0.6 * away - 0.4 * up),
                              up, 480, 360, 60 * M_PI / 180);
  const Eigen::Vector3d shadowed = R * (1.6 * away - up), lit = R * (-2.5 * away - up);
  ASSERT_LT(rayDistance(shadowed / R, sun), 0.8);  // in the full shadow
  for (const auto& p : {shadowed, lit}) {
    ASSERT_GT(rayDistance(cam.eye / R, (p - cam.eye).normalized()), 1.1)  // not hidden
        << p.transpose();
  }
  const Eigen::Vector2d shadowPx = cam.project(cam.toCamera(shadowed));
  const Eigen::Vector2d litPx = cam.project(cam.toCamera(lit));
  ASSERT_TRUE(inside(cam, shadowPx)) << shadowPx.transpose();
  ASSERT_TRUE(inside(cam, litPx)) << litPx.transpose();

  render::RenderStyle style;
  style.sun = sun;
  const cv::Mat without = draw(renderer, planet, cam, style);
  style.boardShadow = true;
  const cv::Mat with = draw(renderer, planet, cam, style);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(at(without, shadowPx)[k], 128);
    EXPECT_NEAR(at(with, shadowPx)[k], 64, 2) << "channel " << k;  // x (1 - 0.5)
    EXPECT_EQ(at(with, litPx)[k], 128) << "channel " << k;
  }
  // Darkening only: no pixel gets brighter, and the darkened pixels are a patch, not the board.
  cv::Mat brighter, darker;
  cv::compare(with, without, brighter, cv::CMP_GT);
  cv::compare(with, without, darker, cv::CMP_LT);
  EXPECT_EQ(cv::countNonZero(brighter.reshape(1)), 0);
  const int darkened = cv::countNonZero(darker.reshape(1)) / 3;
  EXPECT_GT(darkened, 500);
  EXPECT_LT(darkened, cam.width * cam.height / 3);
  RecordProperty("darkened_pixels", std::to_string(darkened));

  style.sun = render::sunDirection({45, -5});
  style.boardShadow = false;
  const cv::Mat belowWithout = draw(renderer, planet, cam, style);
  style.boardShadow = true;
  EXPECT_EQ(cv::norm(draw(renderer, planet, cam, style), belowWithout, cv::NORM_INF), 0.0);
}

// The camera 5 R from the centre, looking at it: the silhouette is a circle about the principal
// point, and a pixel r from it along the image's x sees the ray whose distance from the centre
// is b = 5 R sin(atan(r / fx)). With the sun to the camera's right, the pixel at b = 1.012 R
// (about 3 px outside the silhouette, on the lit side) turns bluer and brighter, and fainter so
// all round; b = 1.12 R (3 glow widths out) and b = 0.8 R (the planet) keep their colour
// exactly.
TEST(RenderAtmosphere, TheRimIsAThinGlowOutsideTheSilhouette) {
  SKIP_WITHOUT_GL();
  const auto planet = testkit::levelTerrain(8);
  const double R = planet.chart().sphereRadius();
  render::EglContext gl;
  render::PlanetRenderer renderer;
  const double distance = 5;
  const auto cam = terrain::Camera::lookAt(
      distance * R * Eigen::Vector3d(1, -0.4, 0.5).normalized(), Eigen::Vector3d::Zero(),
      Eigen::Vector3d::UnitZ(), 800, 600, 40 * M_PI / 180);
  const Eigen::Vector3d right = cam.rotation.row(0).transpose();
  render::RenderStyle style;
  style.sun = (right - 0.3 * cam.rotation.row(1).transpose()).normalized();
  const cv::Mat without = draw(renderer, planet, cam, style);
  style.atmosphere = true;
  const cv::Mat with = draw(renderer, planet, cam, style);
  const auto pixelAt = [&](double b, double side) {
    const double r = cam.fx * std::tan(std::asin(b / distance));
    return Eigen::Vector2d(cam.cx + side * r, cam.cy);
  };
  for (const double side : {1.0, -1.0}) {
    const Eigen::Vector2d glow = pixelAt(1.012, side), far = pixelAt(1.12, side),
                          planetPx = pixelAt(0.8, side);
    ASSERT_TRUE(inside(cam, far)) << far.transpose();
    const cv::Vec3b g = at(with, glow);  // BGR
    EXPECT_EQ(at(without, glow), cv::Vec3b(128, 128, 128)) << "side " << side;
    if (side > 0) {  // the lit side: bright and blue
      EXPECT_GT(int(g[0]), 128 + 25) << "blue";
      EXPECT_GT(int(g[0]) - int(g[2]), 20) << "bluer than red";
    } else {  // the night side: fainter, still blue
      EXPECT_GT(int(g[0]), 128 + 3) << "blue";
      EXPECT_LT(int(g[0]), int(at(with, pixelAt(1.012, 1))[0]));
    }
    EXPECT_EQ(at(with, far), at(without, far)) << "side " << side;
    EXPECT_EQ(at(with, planetPx), at(without, planetPx)) << "side " << side;
    EXPECT_NE(at(without, planetPx), cv::Vec3b(128, 128, 128)) << "the planet is there";
  }
  // All round the silhouette, night side included, the glow is there (faint where unlit).
  for (int k = 0; k < 16; ++k) {
    const double phi = 2 * M_PI * k / 16, r = cam.fx * std::tan(std::asin(1.012 / distance));
    const Eigen::Vector2d px(cam.cx + r * std::cos(phi), cam.cy + r * std::sin(phi));
    EXPECT_GT(int(at(with, px)[0]), 128 + 4) << "at " << px.transpose();
    EXPECT_EQ(at(without, px), cv::Vec3b(128, 128, 128)) << "at " << px.transpose();
  }
}

TEST(RenderSun, AzimuthElevationParseAndBadValuesAreRefusedByName) {
  const render::SunAngles d;
  EXPECT_LT((render::sunDirection(d) - Eigen::Vector3d(1, 1, 1).normalized()).norm(), 1e-15);
  EXPECT_LT((render::sunDirection({90, 0}) - Eigen::Vector3d::UnitY()).norm(), 1e-15);
  EXPECT_LT((render::sunDirection({10, 90}) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  const auto a = render::parseSunAngles(" -30 , 12.5");
  EXPECT_EQ(a.azimuthDeg, -30);
  EXPECT_EQ(a.elevationDeg, 12.5);
  EXPECT_EQ(render::parseSunAngles("400,-90").elevationDeg, -90);
  for (const char* bad : {"", "45", "45,", ",30", "a,b", "1,2,3", "nan,10", "10,nan", "10,NaN",
                          "inf,3", "10,91", "10,-90.5", "10,30x", "10;30"}) {
    try {
      render::parseSunAngles(bad);
      ADD_FAILURE() << "'" << bad << "' was accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--sun"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}
