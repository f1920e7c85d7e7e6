// Which height tiles a view asks for (render/tile_requests.hpp), without OpenGL; and, on
// headless OpenGL, that the pixels find the level they ask for in the tiles the view held.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <set>

#include "gl_test.hpp"
#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "render/tile_requests.hpp"
#include "terrain/relief.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

terrain::Terrain reliefPlanet(int n) {
  auto chart = testkit::earthChart(n);
  terrain::ReliefParams p;
  p.seed = 11;
  return terrain::Terrain(chart, terrain::generateRelief(*chart, p));
}

terrain::Camera above(double R, double altitude, int width = 320, int height = 240) {
  const Eigen::Vector3d dir = Eigen::Vector3d(1, 0.3, 0.4).normalized();
  const Eigen::Vector3d ahead = dir.cross(Eigen::Vector3d::UnitZ()).normalized();
  return terrain::Camera::lookAt((R + altitude) * dir,
                                 R * (dir + std::min(1.0, 2 * altitude / R) * ahead).normalized(),
                                 Eigen::Vector3d::UnitZ(), width, height, 60 * M_PI / 180);
}

}  // namespace

TEST(TileRequests, EveryTileHasOneIndexAndTheLevelsHalve) {
  for (int n : {5, 7, 10, 13}) {
    const auto p = render::TilePyramid::forGrid(core::GridSize(n));
    EXPECT_EQ(p.tileCells, std::min(128, 1 << n));
    EXPECT_EQ(p.tilesPerSide(p.coarsest), 1);
    EXPECT_EQ(p.levelCells(p.coarsest), p.tileCells);
    std::size_t expected = 0;
    for (int l = 0; l <= p.coarsest; ++l) {
      EXPECT_EQ(p.levelCells(l), p.tilesPerSide(l) * p.tileCells);
      expected += std::size_t(p.tilesPerSide(l)) * std::size_t(p.tilesPerSide(l));
    }
    ASSERT_EQ(p.tileCount(), expected);
    for (std::size_t i = 0; i < p.tileCount(); ++i) ASSERT_EQ(p.index(p.key(i)), i) << n;
    EXPECT_EQ(p.key(0), (render::TileKey{p.coarsest, 0, 0}));  // the always-held ones first
  }
}

// Every vertex of a triangle lies in a tile the view asks for at the triangle's level; a closer
// view asks for finer levels; a bias makes every request coarser, down to the one coarsest tile.
TEST(TileRequests, TheTilesCoverEachTriangleAtItsLevel) {
  const auto planet = reliefPlanet(11);
  const double R = planet.chart().radius();
  const int side = planet.grid().side();
  const auto pyramid = render::TilePyramid::forGrid(planet.grid());
  int previousFinest = pyramid.coarsest + 1;
  for (double altitude : {2e6, 3e5, 3e4}) {
    terrain::Tessellator tess;
    const auto cam = above(R, altitude);
    const auto& mesh = tess.tessellate(planet, cam, {});
    const auto wishes = render::tileWishes(pyramid, mesh, cam, side);
    ASSERT_GT(wishes.size(), mesh.triangleCount() / 4);
    std::vector<std::uint32_t> stamp, tiles;
    render::tilesFor(pyramid, wishes, 0, stamp, 1, tiles);
    const std::set<std::uint32_t> held(tiles.begin(), tiles.end());
    ASSERT_EQ(held.size(), tiles.size());  // each once
    int finest = pyramid.coarsest;
    for (const auto& w : wishes) {
      ASSERT_GE(w.level, 0);
      ASSERT_LE(w.level, pyramid.coarsest);
      finest = std::min(finest, w.level);
      const int span = pyramid.tileCells << w.level, last = pyramid.tilesPerSide(w.level) - 1;
      for (int u : {w.u0, w.u1})
        for (int v : {w.v0, w.v1})
          ASSERT_TRUE(held.count(std::uint32_t(
              pyramid.index({w.level, std::min(u / span, last), std::min(v / span, last)}))));
    }
    EXPECT_LE(finest, previousFinest) << altitude;
    previousFinest = finest;
    render::tilesFor(pyramid, wishes, pyramid.coarsest, stamp, 2, tiles);
    EXPECT_EQ(tiles, std::vector<std::uint32_t>{0u});
  }
  EXPECT_EQ(previousFinest, 0);  // 30 km up reads full resolution
}

// On the GPU: with room for the view, almost no pixel reads a level coarser than its footprint
// asks (the CPU's estimate from the triangles against the shader's fwidth; < 1 % of the planet's
// pixels, where a triangle's corner is nearer than its mean depth says; measured: none); with a
// budget too small for the view, the same count sees the pixels that had to go coarser.
TEST(TileRequests, PixelsFindTheLevelTheirFootprintAsksFor) {
  SKIP_WITHOUT_GL();
  const auto planet = reliefPlanet(11);
  const double R = planet.chart().radius();
  render::EglContext gl;
  render::PlanetRenderer renderer, starved;
  starved.setHeightCacheBudget(7 * 131 * 131 * sizeof(float));
  render::RenderStyle style;
  style.showTileLevels = true;
  int starvedViews = 0;
  for (double altitude : {2e7, 2e6, 3e5, 3e4}) {
    terrain::Tessellator tess;
    const auto cam = above(R, altitude);
    const auto& mesh = tess.tessellate(planet, cam, {});
    auto count = [](const cv::Mat& image, int& planetPixels, int& missed) {
      planetPixels = missed = 0;
      for (int y = 0; y < image.rows; ++y)
        for (int x = 0; x < image.cols; ++x) {
          const cv::Vec3b c = image.at<cv::Vec3b>(y, x);  // BGR
          if (c == cv::Vec3b(0, 0, 0)) continue;
          ++planetPixels;
          missed += c == cv::Vec3b(0, 0, 255);
        }
    };
    int planetPixels = 0, missed = 0;
    count(starved.renderAR({}, planet, mesh, cam, style), planetPixels, missed);
    if (starved.stats().heightLevelBias > 0) {
      ++starvedViews;
      EXPECT_GT(missed, planetPixels / 10) << altitude;
    }
    count(renderer.renderAR({}, planet, mesh, cam, style), planetPixels, missed);
    ASSERT_GT(planetPixels, 5000) << altitude;
    EXPECT_LT(missed, planetPixels / 100)
        << altitude << " m up: " << missed << " of " << planetPixels;
    std::printf("[ info ] %.0f m up: %d of %d pixels read a coarser level than asked, %zu tiles\n",
                altitude, missed, planetPixels, renderer.stats().heightTilesNeeded);
  }
  EXPECT_GE(starvedViews, 2);
}
