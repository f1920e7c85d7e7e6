// Which height tiles a view asks for (render/tile_requests.hpp), without OpenGL; and, on
// headless OpenGL, that the pixels find the level they ask for in the tiles the view held.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <set>

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <optional>
#include <string>

#include "core/cylinder_chart.hpp"
#include "core/torus_chart.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "gl_test.hpp"
#include "render/egl_context.hpp"
#include "render/height_tile_cache.hpp"
#include "render/planet_renderer.hpp"
#include "render/tile_requests.hpp"
#include "terrain/tessellator.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

// Every texel of the tiles the cache holds, apron included, with the level-0 grid position it
// stands for: f(tile key, i, j, u, v, texel), which returns whether to go on.
template <class F>
void forEachHeldTexel(const render::HeightTileCache& cache, F&& f) {
  const auto& p = cache.pyramid();
  const int S = cache.slotSide();
  std::vector<float> texels(std::size_t(S) * std::size_t(S) * std::size_t(cache.layers()));
  glBindTexture(GL_TEXTURE_2D_ARRAY, cache.tiles());
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTexImage(GL_TEXTURE_2D_ARRAY, 0, GL_RED, GL_FLOAT, texels.data());
  for (std::size_t tile = 0; tile < p.tileCount(); ++tile) {
    const int layer = cache.layerOf(tile);
    if (layer < 0) continue;
    const render::TileKey k = p.key(tile);
    const int step = 1 << k.level;
    for (int j = 0; j < S; ++j)
      for (int i = 0; i < S; ++i) {
        const int u = (k.tx * p.tileCells + i - 1) * step, v = (k.ty * p.tileCells + j - 1) * step;
        if (!f(k, i, j, u, v,
               texels[(std::size_t(layer) * std::size_t(S) + std::size_t(j)) * std::size_t(S) +
                      std::size_t(i)]))
          return;
      }
  }
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
  const auto planet = testkit::reliefTerrain(11, 11);
  const double R = planet.chart().sphereRadius();
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
  const auto planet = testkit::reliefTerrain(11, 11);
  const double R = planet.chart().sphereRadius();
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

// The tiles hold the heights they stand for, aprons included: across a seam the other side's
// column, across a folded side of the octahedral chart the twin's side (the apron texel d steps
// beyond a side vertex holds the vertex d steps inside from that vertex's twin, as Chart::twins
// says), and after an edit near a fold the tiles across it are sent again.
TEST(TileRequests, TilesAndTheirApronsHoldTheHeightsAcrossFoldsAndSeams) {
  SKIP_WITHOUT_GL();
  render::EglContext gl;
  for (const bool octahedral : {true, false}) {
    auto planet = octahedral ? testkit::bumpyOctahedralTerrain(9, 4, 5000.0)
                             : testkit::bumpyTerrain(9, 4, 5000.0);
    const core::Chart& chart = planet.chart();
    const int m = planet.grid().m();
    const double R = chart.sphereRadius();
    render::HeightTileCache cache;
    std::string why;
    // Expected height of level-0 position (u, v), one step outside the grid at most per axis.
    auto expected = [&](int u, int v) -> std::optional<float> {
      if (u >= 0 && u <= m && v >= 0 && v <= m) return planet.height(u, v);
      if ((u < 0 || u > m) && (v < 0 || v > m)) return std::nullopt;  // a corner's diagonal
      if (!octahedral) {
        if (v < 0 || v > m) return planet.height(u, std::clamp(v, 0, m));  // clamped at a pole
        return planet.height(((u % m) + m) % m, v);                        // the seam
      }
      // Beyond a folded side: from the side vertex, the twin, then as far inside.
      const bool beyondV = v < 0 || v > m;
      const int sideU = beyondV ? u : (u < 0 ? 0 : m), sideV = beyondV ? (v < 0 ? 0 : m) : v;
      const int d = beyondV ? std::abs(v - sideV) : std::abs(u - sideU);
      // Beyond a corner (the south pole, where four quadrants meet) no one neighbour is right.
      if ((sideU == 0 || sideU == m) && (sideV == 0 || sideV == m)) return std::nullopt;
      core::GridPoint t[4];
      const int n = chart.twins(sideU, sideV, t);
      for (int k = 0; k < n; ++k) {
        if (t[k].u == sideU && t[k].v == sideV && n > 1) continue;
        const int iu = beyondV ? t[k].u : (t[k].u == 0 ? d : m - d);
        const int iv = beyondV ? (t[k].v == 0 ? d : m - d) : t[k].v;
        return planet.height(iu, iv);
      }
      return planet.height(sideU, sideV);  // a side's midpoint is its own twin: mirrored in place
    };
    // The first wrong texel, or too few apron texels checked: the test ASSERTs on the result.
    auto check = [&](const char* when) -> testing::AssertionResult {
      int apron = 0;
      testing::AssertionResult result = testing::AssertionSuccess();
      forEachHeldTexel(cache, [&](const render::TileKey& k, int i, int j, int u, int v, float got) {
        const auto want = expected(u, v);
        if (!want) return true;
        if (got != *want) {
          result = testing::AssertionFailure()
                   << chart.name() << " " << when << ": tile " << k.level << "/" << k.tx << ","
                   << k.ty << " texel (" << i << "," << j << ") = grid (" << u << "," << v
                   << ") holds " << got << ", the grid " << *want;
          return false;
        }
        apron += u < 0 || u > m || v < 0 || v > m;
        return true;
      });
      if (result && apron <= 100)
        return testing::AssertionFailure()
               << chart.name() << " " << when << ": only " << apron << " apron texels";
      return result;
    };
    // A view over the fold of side u = 0 south of the equator (lat-long: over the seam there).
    const Eigen::Vector3d d = Eigen::Vector3d(-0.7, 0.01, -0.7).normalized();
    const auto cam = terrain::Camera::lookAt((R + 1.5e6) * d, R * d, d.unitOrthogonal(), 320, 240,
                                             70 * M_PI / 180);
    terrain::Tessellator tess;
    ASSERT_TRUE(cache.sync(planet, tess.tessellate(planet, cam, {}), cam, why)) << why;
    ASSERT_TRUE(check("first view"));
    // An edit on the fold, then the same view: the tiles across it follow.
    edit::EditPipeline pipe(planet);
    edit::BrushSettings b;
    b.radius = 0.05 * R;
    b.strength = 2500;
    pipe.apply(edit::GaussianBrush(b), {R * d, 0.0});
    ASSERT_TRUE(cache.sync(planet, tess.tessellate(planet, cam, {}), cam, why)) << why;
    ASSERT_TRUE(check("after an edit"));
    // One vertex just inside a side (no twin of its own): the apron beyond the side's mirror
    // point, in the tiles across the fold, follows it too.
    for (const auto& [u, v] : {std::pair{1, m / 2 + 37}, std::pair{m / 2 - 53, 1}}) {
      planet.mutableHeights()[planet.grid().index(u, v)] += 700.0f;
      planet.commitEdit(terrain::VertexBox{u, u, v, v});
    }
    ASSERT_TRUE(cache.sync(planet, tess.tessellate(planet, cam, {}), cam, why)) << why;
    ASSERT_TRUE(check("after single vertices beside the sides"));
  }
}

// The torus's tiles wrap both ways (its v seam through core::Chart::continued), the cylinder's
// round the axis and clamp at its open ends: every texel, apron included, holds the grid
// vertex there, after the first view, an edit at the seams' crossing and single vertices just
// inside the sides.
TEST(TileRequests, TorusAndCylinderApronsWrapAcrossTheirSeams) {
  SKIP_WITHOUT_GL();
  render::EglContext gl;
  for (const bool torus : {true, false}) {
    std::shared_ptr<const core::Chart> chart;
    if (torus)
      chart = std::make_shared<core::TorusChart>(core::GridSize(9), 4.0e6, 1.5e6);
    else
      chart = std::make_shared<core::CylinderChart>(core::GridSize(9), 2.0e6, 8.0e6);
    terrain::Terrain planet(chart, testkit::bumpyHeights(*chart, 4, 5000.0));
    const int m = planet.grid().m();
    render::HeightTileCache cache;
    std::string why;
    auto expected = [&](int u, int v) -> float {
      const int w = ((u % m) + m) % m;  // both seam round the u axis
      if (torus) return planet.height(w, ((v % m) + m) % m);
      return planet.height(w, std::clamp(v, 0, m));  // the open ends clamp
    };
    // The first wrong texel, or too few apron texels beyond the v sides: the test ASSERTs on it.
    auto check = [&](const char* when) -> testing::AssertionResult {
      int apronV = 0;
      testing::AssertionResult result = testing::AssertionSuccess();
      forEachHeldTexel(cache, [&](const render::TileKey& k, int i, int j, int u, int v, float got) {
        if (got != expected(u, v)) {
          result = testing::AssertionFailure()
                   << chart->name() << " " << when << ": tile " << k.level << "/" << k.tx << ","
                   << k.ty << " texel (" << i << "," << j << ") = grid (" << u << "," << v
                   << ") holds " << got << ", the grid " << expected(u, v);
          return false;
        }
        apronV += v < 0 || v > m;
        return true;
      });
      if (result && apronV <= 100)
        return testing::AssertionFailure() << chart->name() << " " << when << ": only " << apronV
                                           << " apron texels beyond the v sides";
      return result;
    };
    // Over the seams' crossing (the torus's corner; the cylinder's seam at its end v = 0).
    const Eigen::Vector3d target = chart->position(0, 0, 0), n = chart->up(0, 0);
    const auto cam = terrain::Camera::lookAt(target + 1.5e6 * n, target, n.unitOrthogonal(), 320,
                                             240, 70 * M_PI / 180);
    terrain::Tessellator tess;
    ASSERT_TRUE(cache.sync(planet, tess.tessellate(planet, cam, {}), cam, why)) << why;
    ASSERT_TRUE(check("first view"));
    edit::EditPipeline pipe(planet);
    edit::BrushSettings b;
    b.radius = 3.0e5;
    b.strength = 2500;
    pipe.apply(edit::GaussianBrush(b), {target, 0.0});
    ASSERT_TRUE(cache.sync(planet, tess.tessellate(planet, cam, {}), cam, why)) << why;
    ASSERT_TRUE(check("after an edit"));
    for (const auto& [u, v] : {std::pair{1, 3}, std::pair{3, 1}, std::pair{m - 1, m - 2}}) {
      planet.mutableHeights()[planet.grid().index(u, v)] += 700.0f;
      planet.commitEdit(terrain::VertexBox{u, u, v, v});
    }
    ASSERT_TRUE(cache.sync(planet, tess.tessellate(planet, cam, {}), cam, why)) << why;
    ASSERT_TRUE(check("after single vertices beside the sides"));
  }
}
