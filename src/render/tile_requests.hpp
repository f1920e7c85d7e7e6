#pragma once
// Which tiles of the height pyramid a view needs (render/height_tile_cache.hpp). Level L of the
// pyramid is the grid's every 2^L-th vertex, cut into square tiles of `tileCells` cells; the
// coarsest level is one tile. A pixel of the planet reads the level where its footprint spans
// one to two texels (the shader takes the largest of fwidth's two grid axes, as here), so a
// view needs, for each triangle, that level's tiles under the triangle. Pure CPU: the cache
// asks for it and tests check it without OpenGL.
#include <cstdint>
#include <vector>

#include "core/grid.hpp"
#include "terrain/camera.hpp"
#include "terrain/mesh.hpp"

namespace ps::render {

struct TileKey {
  int level = 0, tx = 0, ty = 0;
  bool operator==(const TileKey&) const = default;
};

struct TilePyramid {
  int m = 0;          // the grid's cells per side (a power of two)
  int tileCells = 0;  // cells per tile side at every level
  int coarsest = 0;   // the level of one tile

  // Tiles of min(maxTileCells, m) cells; maxTileCells a power of two.
  static TilePyramid forGrid(const core::GridSize& grid, int maxTileCells = 128);
  int tilesPerSide(int level) const { return 1 << (coarsest - level); }
  std::size_t tileCount() const;                          // over every level
  std::size_t index(const TileKey& k) const;              // 0 .. tileCount() - 1
  TileKey key(std::size_t index) const;                   // inverse of index()
  int levelCells(int level) const { return m >> level; }  // cells per side at `level`
};

// A triangle's wish: the level its pixels' footprint asks for (0 = full resolution) and its
// grid box (level-0 vertices, inclusive).
struct TileWish {
  int level = 0;
  int u0 = 0, u1 = 0, v0 = 0, v1 = 0;
};

// One wish per triangle of `mesh` that the camera may see (triangles wholly off one side of the
// image are left out). The footprint is the grid-per-pixel Jacobian of the triangle's screen
// projection, scaled by its nearest vertex's depth over the mean (perspective makes the near
// corner finer); a triangle reaching behind the camera asks for level 0.
std::vector<TileWish> tileWishes(const TilePyramid& pyramid, const terrain::Mesh& mesh,
                                 const terrain::Camera& camera, int gridSide);

// The tiles the wishes cover with every level made `bias` coarser (clamped to the coarsest),
// each once, in flat indices (TilePyramid::index); `stamp` is scratch of tileCount() entries.
void tilesFor(const TilePyramid& pyramid, const std::vector<TileWish>& wishes, int bias,
              std::vector<std::uint32_t>& stamp, std::uint32_t stampValue,
              std::vector<std::uint32_t>& out);

}  // namespace ps::render
