#pragma once
// The planet's heights on the GPU, one texel per grid vertex (R32F, the chart's own parameter
// space), so that every pixel of the planet can take its normal, tint and contour lines from
// the full-resolution surface whatever the mesh (render/planet_renderer.hpp). After an edit only
// the rows and columns it changed are sent (terrain::Terrain::changedSince). Needs a current
// OpenGL 3.3 context.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "terrain/terrain.hpp"

namespace ps::render {

class HeightTexture {
 public:
  HeightTexture() = default;
  ~HeightTexture();
  HeightTexture(const HeightTexture&) = delete;
  HeightTexture& operator=(const HeightTexture&) = delete;

  // Makes the texture hold `planet`'s heights now: the first time (or for another planet)
  // the whole grid, afterwards the regions changed since the last call. False, with `why`,
  // when this context cannot hold it (a grid side above GL_MAX_TEXTURE_SIZE, no float
  // textures, out of memory): the caller draws without it.
  bool sync(const terrain::Terrain& planet, std::string& why);

  unsigned texture() const { return texture_; }  // 0 after a failed sync
  int side() const { return side_; }
  std::size_t bytes() const { return std::size_t(side_) * std::size_t(side_) * sizeof(float); }
  std::size_t lastUploadBytes() const { return lastUpload_; }  // sent by the last sync

 private:
  void release();
  void sendRows(const terrain::Terrain& planet, int u0, int u1, int v0, int v1);

  unsigned texture_ = 0;
  int side_ = 0;
  const terrain::Terrain* planet_ = nullptr;
  std::uint64_t revision_ = 0;
  std::size_t lastUpload_ = 0;
  std::vector<terrain::GridRegion> changed_;
};

}  // namespace ps::render
