#pragma once
// The planet's heights on the GPU for per-pixel shading, as a tile cache of a set size: a
// pyramid of levels (level L: every 2^L-th grid vertex, in the chart's own (u, v); tiles of 128
// cells with a one-texel apron so that a tile alone serves a pixel's bilinear samples and
// differences) of which only the tiles the view needs are resident, in one R32F texture array,
// and a page table (R16UI, one mip level per pyramid level: 0 = not resident, else the layer +
// 1) through which the shader finds, for each pixel, the level its footprint asks for or the
// nearest coarser one held. The coarsest two levels are always held.
//
// Memory is at most the budget whatever the grid (64 MiB by default: 977 tiles; the array starts
// at 32 tiles and doubles as views need more: bench render's views of the 4097^2 planet need
// 5-62), against 4 B per vertex for a whole float texture (64 MiB at 4097^2, 256 MiB at 8193^2,
// 1 GiB at 16385^2). After an edit only the changed texels of the held tiles are sent
// (terrain::Terrain::changedSince); a tile that becomes needed is sent
// whole. Needs a current OpenGL 3.3 context.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "render/tile_requests.hpp"
#include "terrain/camera.hpp"
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::render {

class HeightTileCache {
 public:
  static constexpr std::size_t kDefaultBudgetBytes = std::size_t(64) << 20;
  static constexpr int kMaxTileCells = 128;

  explicit HeightTileCache(std::size_t budgetBytes = kDefaultBudgetBytes) : budget_(budgetBytes) {}
  ~HeightTileCache();
  HeightTileCache(const HeightTileCache&) = delete;
  HeightTileCache& operator=(const HeightTileCache&) = delete;

  // Makes the cache hold what `camera` needs to shade `mesh` of `planet` now: tiles the view
  // needs and lacks are sent, texels an edit changed in held tiles are sent again. When the
  // view needs more tiles than the budget holds, every level is made coarser until it fits.
  // False, with `why`, when this context cannot hold the cache (a budget below 6 tiles, no
  // float texture arrays, out of memory): the caller draws without it.
  bool sync(const terrain::Terrain& planet, const terrain::Mesh& mesh,
            const terrain::Camera& camera, std::string& why);

  unsigned tiles() const { return tiles_; }  // GL_TEXTURE_2D_ARRAY, 0 after a failed sync
  unsigned pageTable() const { return pageTable_; }
  const TilePyramid& pyramid() const { return pyramid_; }
  int slotSide() const { return pyramid_.tileCells + 3; }
  std::size_t bytes() const;                                   // GPU memory held
  std::size_t lastUploadBytes() const { return lastUpload_; }  // sent by the last sync
  std::size_t residentTiles() const { return resident_; }
  std::size_t neededTiles() const { return needed_.size(); }  // by the last view
  int levelBias() const { return bias_; }  // levels made coarser to fit the budget (0: none)
  // The array layer that holds tile `tile` (TilePyramid::index), or -1 (for tests and tools).
  int layerOf(std::size_t tile) const {
    return tile < slotOf_.size() ? int(slotOf_[tile]) - 1 : -1;
  }
  int layers() const { return slots_; }

 private:
  void release();
  bool allocate(const terrain::Terrain& planet, std::string& why);
  bool reserve(std::size_t slots);
  void request(const terrain::Mesh& mesh, const terrain::Camera& camera, int side);
  void sendTile(const terrain::Terrain& planet, int slot, const TileKey& key, int i0, int i1,
                int j0, int j1);
  void sendChanges(const terrain::Terrain& planet);
  void sendPageTable();

  std::size_t budget_;
  unsigned tiles_ = 0, pageTable_ = 0;
  TilePyramid pyramid_;
  int slots_ = 0, maxSlots_ = 0;  // layers of the array now, and what the budget allows
  bool grew_ = true;              // false when growing the array failed (out of memory)
  const terrain::Terrain* planet_ = nullptr;
  std::uint64_t revision_ = 0;
  std::size_t lastUpload_ = 0, resident_ = 0;
  int bias_ = 0;
  // The view the residency was chosen for.
  const terrain::Mesh* mesh_ = nullptr;
  std::uint64_t meshGeneration_ = 0;
  terrain::Camera camera_;
  // Per tile (flat index): its slot + 1 (0: not held); per slot: its tile and when last needed.
  std::vector<std::uint16_t> slotOf_;
  std::vector<std::uint32_t> tileIn_, lastNeeded_;
  std::vector<std::uint32_t> freeSlots_, stamp_, needed_;
  std::uint32_t frame_ = 0, stampValue_ = 0;
  bool pageTableDirty_ = false;
  std::vector<std::uint16_t> pageScratch_;
  std::vector<float> texels_;
  std::vector<terrain::VertexBox> changed_;
};

}  // namespace ps::render
