#include "render/height_tile_cache.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <vector>

namespace ps::render {

namespace {
constexpr std::uint32_t kNoTile = std::numeric_limits<std::uint32_t>::max();
}

HeightTileCache::~HeightTileCache() {
  release();
}

void HeightTileCache::release() {
  if (tiles_) glDeleteTextures(1, &tiles_);
  if (pageTable_) glDeleteTextures(1, &pageTable_);
  tiles_ = pageTable_ = 0;
  slots_ = 0;
  resident_ = 0;
  planet_ = nullptr;
  mesh_ = nullptr;
}

std::size_t HeightTileCache::bytes() const {
  if (!tiles_) return 0;
  std::size_t page = 0;
  for (int l = 0; l <= pyramid_.coarsest; ++l)
    page += std::size_t(pyramid_.tilesPerSide(l)) * std::size_t(pyramid_.tilesPerSide(l));
  const std::size_t s = std::size_t(slotSide());
  return std::size_t(slots_) * s * s * sizeof(float) + page * sizeof(std::uint16_t);
}

bool HeightTileCache::allocate(const terrain::Terrain& planet, std::string& why) {
  release();
  pyramid_ = TilePyramid::forGrid(planet.grid(), kMaxTileCells);
  const std::size_t s = std::size_t(slotSide()), slotBytes = s * s * sizeof(float);
  const std::size_t total = pyramid_.tileCount();
  // The coarsest two levels stay held (every pixel finds a tile), and one more for the view.
  const std::size_t always = pyramid_.coarsest > 0 ? 5 : 1;
  GLint maxLayers = 0;
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &maxLayers);
  // The page table (2 B per tile of every level) comes out of the budget too.
  const std::size_t pageBytes = total * sizeof(std::uint16_t);
  const std::size_t room = budget_ > pageBytes ? (budget_ - pageBytes) / slotBytes : 0;
  const std::size_t slots = std::min({room, total, std::size_t(std::max(0, maxLayers)),
                                      std::size_t(std::numeric_limits<std::uint16_t>::max() - 1)});
  if (slots < std::min(total, always + 1)) {
    why = "the height tile cache's budget (" + std::to_string(budget_) + " B) holds " +
          std::to_string(slots) + " tiles of " + std::to_string(slotBytes) + " B, fewer than the " +
          std::to_string(std::min(total, always + 1)) + " it needs";
    return false;
  }
  while (glGetError() != GL_NO_ERROR) {
  }
  maxSlots_ = int(slots);
  planet_ = &planet;
  glGenTextures(1, &pageTable_);
  glBindTexture(GL_TEXTURE_2D, pageTable_);
  std::vector<std::uint16_t> zeros(std::size_t(pyramid_.tilesPerSide(0)) *
                                   std::size_t(pyramid_.tilesPerSide(0)));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (int l = 0; l <= pyramid_.coarsest; ++l)
    glTexImage2D(GL_TEXTURE_2D, l, GL_R16UI, pyramid_.tilesPerSide(l), pyramid_.tilesPerSide(l), 0,
                 GL_RED_INTEGER, GL_UNSIGNED_SHORT, zeros.data());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, pyramid_.coarsest);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindTexture(GL_TEXTURE_2D, 0);
  slotOf_.assign(total, 0);
  tileIn_.clear();
  lastNeeded_.clear();
  freeSlots_.clear();
  // Room for a first view; grown (to the budget) when a view needs more.
  if (glGetError() != GL_NO_ERROR || !reserve(std::min(slots, std::size_t(32)))) {
    release();
    why = "no room for float height tiles (" + std::to_string(pageBytes) + " B of page table)";
    return false;
  }
  stamp_.assign(total, 0);
  frame_ = 0;
  revision_ = planet.revision();
  return true;
}

bool HeightTileCache::reserve(std::size_t slots) {
  // A new array of `slots` layers; the held tiles are sent again into the same layers (GL 3.3
  // has no copy between textures, and the heights are at hand).
  const std::size_t s = std::size_t(slotSide());
  GLuint grown = 0;
  glGenTextures(1, &grown);
  glBindTexture(GL_TEXTURE_2D_ARRAY, grown);
  glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_R32F, GLsizei(s), GLsizei(s), GLsizei(slots), 0, GL_RED,
               GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  if (glGetError() != GL_NO_ERROR) {
    glDeleteTextures(1, &grown);
    return false;
  }
  if (tiles_) glDeleteTextures(1, &tiles_);
  tiles_ = grown;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  for (std::size_t slot = 0; slot < tileIn_.size(); ++slot)
    if (tileIn_[slot] != kNoTile)
      sendTile(*planet_, int(slot), pyramid_.key(tileIn_[slot]), 0, int(s) - 1, 0, int(s) - 1);
  const std::size_t old = tileIn_.size();
  tileIn_.resize(slots, kNoTile);
  lastNeeded_.resize(slots, 0);
  for (std::size_t i = slots; i-- > old;) freeSlots_.push_back(std::uint32_t(i));
  // Free slots are taken from the back: the lowest first.
  std::sort(freeSlots_.begin(), freeSlots_.end(), std::greater<>());
  slots_ = int(slots);
  return true;
}

void HeightTileCache::sendTile(const terrain::Terrain& planet, int slot, const TileKey& key, int i0,
                               int i1, int j0, int j1) {
  // Slot texel (i, j) is level texel (tx T + i - 1, ty T + j - 1): the apron repeats the
  // neighbour across a seam the chart wraps or a side it folds, and the edge elsewhere (as
  // clamping would).
  const int T = pyramid_.tileCells, mL = pyramid_.levelCells(key.level),
            side = planet.grid().side(), step = 1 << key.level;
  const bool wraps = planet.chart().wrapsU(), glued = planet.chart().gluesSidesBeyondSeam();
  const float* h = planet.heights().data();
  const int w = i1 - i0 + 1, rows = j1 - j0 + 1;
  texels_.resize(std::size_t(w) * std::size_t(rows));
  for (int j = 0; j < rows; ++j) {
    const int gvRaw = key.ty * T + j0 + j - 1;
    const int gv = std::clamp(gvRaw, 0, mL);
    const std::size_t row = std::size_t(gv * step) * std::size_t(side);
    for (int i = 0; i < w; ++i) {
      const int guRaw = key.tx * T + i0 + i - 1;
      float& texel = texels_[std::size_t(j) * std::size_t(w) + std::size_t(i)];
      if (glued && (guRaw < 0 || guRaw > mL || gvRaw < 0 || gvRaw > mL)) {
        // Beyond a glued side (core::Chart::continued: a mirrored side's mirror, the torus's
        // other end of its v seam).
        const core::GridPoint p = planet.chart().continued(guRaw * step, gvRaw * step);
        texel = h[std::size_t(p.v) * std::size_t(side) + std::size_t(p.u)];
        continue;
      }
      const int gu = wraps ? ((guRaw % mL) + mL) % mL : std::clamp(guRaw, 0, mL);
      texel = h[row + std::size_t(gu * step)];
    }
  }
  glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, i0, j0, slot, w, rows, 1, GL_RED, GL_FLOAT,
                  texels_.data());
  lastUpload_ += texels_.size() * sizeof(float);
}

void HeightTileCache::sendChanges(const terrain::Terrain& planet) {
  // Per held tile, the box of its texels any changed vertex feeds (one texel more each way:
  // the apron's clamped and wrapped copies), then one upload per tile.
  const int S = slotSide(), T = pyramid_.tileCells;
  struct Box {
    int i0 = 1 << 30, i1 = -1, j0 = 1 << 30, j1 = -1;
  };
  std::vector<Box> dirty(static_cast<std::size_t>(slots_));
  const bool wraps = planet.chart().wrapsU();
  // On a chart that glues its sides beyond a u seam, a changed vertex near a side is also the
  // apron texel of the tiles across it: each changed region is looked at from there too, as the
  // region it is beyond that side (outside the grid; core::Chart::continued maps it back).
  std::vector<terrain::VertexBox> looked(changed_.begin(), changed_.end());
  const core::Gluing gl = planet.chart().gluing();
  const int m = planet.grid().m();
  for (const terrain::VertexBox& r : changed_) {
    if (gl.vSides == core::SideGluing::kMirror) {
      looked.push_back({m - r.uEnd, m - r.uBegin, -r.vEnd, -r.vBegin});
      looked.push_back({m - r.uEnd, m - r.uBegin, 2 * m - r.vEnd, 2 * m - r.vBegin});
    } else if (gl.vSides == core::SideGluing::kSeam) {
      looked.push_back({r.uBegin, r.uEnd, r.vBegin - m, r.vEnd - m});
      looked.push_back({r.uBegin, r.uEnd, r.vBegin + m, r.vEnd + m});
    }
    if (gl.uSides == core::SideGluing::kMirror) {
      looked.push_back({-r.uEnd, -r.uBegin, m - r.vEnd, m - r.vBegin});
      looked.push_back({2 * m - r.uEnd, 2 * m - r.uBegin, m - r.vEnd, m - r.vBegin});
    }
  }
  for (const terrain::VertexBox& r : looked) {
    const auto columns = [&](auto&& f) {
      if (r.uBegin < 0 || r.uEnd > planet.grid().m()) {
        if (!planet.chart().wrapsU()) return f(r.uBegin, r.uEnd);  // beyond a fold: as is
      }
      r.forEachColumnRange(planet.grid(), f);
    };
    columns([&](int u0, int u1) {
      for (int slot = 0; slot < slots_; ++slot) {
        if (tileIn_[std::size_t(slot)] == kNoTile) continue;
        const TileKey k = pyramid_.key(tileIn_[std::size_t(slot)]);
        const int L = k.level, step = 1 << L, mL = pyramid_.levelCells(L);
        const int gu0 = (u0 + step - 1) >> L, gu1 = u1 >> L;
        const int gv0 = (r.vBegin + step - 1) >> L, gv1 = r.vEnd >> L;
        if (gu0 > gu1 || gv0 > gv1) continue;  // no vertex of this level changed
        const int j0 = std::max(0, gv0 - 1 - k.ty * T + 1),
                  j1 = std::min(S - 1, gv1 + 1 - k.ty * T + 1);
        if (j0 > j1) continue;
        for (int shift : {0, -mL, mL}) {
          if (shift != 0 && !wraps) continue;
          const int i0 = std::max(0, gu0 - 1 + shift - k.tx * T + 1),
                    i1 = std::min(S - 1, gu1 + 1 + shift - k.tx * T + 1);
          if (i0 > i1) continue;
          Box& b = dirty[std::size_t(slot)];
          b = {std::min(b.i0, i0), std::max(b.i1, i1), std::min(b.j0, j0), std::max(b.j1, j1)};
        }
      }
    });
  }
  glBindTexture(GL_TEXTURE_2D_ARRAY, tiles_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  for (int slot = 0; slot < slots_; ++slot) {
    const Box& b = dirty[std::size_t(slot)];
    if (b.i1 >= 0)
      sendTile(planet, slot, pyramid_.key(tileIn_[std::size_t(slot)]), b.i0, b.i1, b.j0, b.j1);
  }
}

void HeightTileCache::request(const terrain::Mesh& mesh, const terrain::Camera& camera, int side) {
  ++frame_;
  const std::vector<TileWish> wishes = tileWishes(pyramid_, mesh, camera, side);
  // The coarsest two levels, always: pixels whose level is not held find one there.
  const std::size_t always = pyramid_.coarsest > 0 ? 5 : 1;
  for (bias_ = 0;; ++bias_) {
    ++stampValue_;
    tilesFor(pyramid_, wishes, bias_, stamp_, stampValue_, needed_);
    for (std::uint32_t i = 0; i < always; ++i)
      if (stamp_[i] != stampValue_) {
        stamp_[i] = stampValue_;
        needed_.push_back(i);
      }
    if (needed_.size() <= std::size_t(maxSlots_) || bias_ >= pyramid_.coarsest) break;
  }
  if (needed_.size() > std::size_t(slots_))
    grew_ = reserve(
        std::min(std::size_t(maxSlots_), std::max(needed_.size(), 2 * std::size_t(slots_))));
  if (!grew_) return;
  for (std::uint32_t i : needed_)
    if (slotOf_[i]) lastNeeded_[slotOf_[i] - 1u] = frame_;
  glBindTexture(GL_TEXTURE_2D_ARRAY, tiles_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  std::size_t scan = 0;  // slots are taken least recently needed first
  std::vector<std::uint32_t> order;
  for (std::uint32_t i : needed_) {
    if (slotOf_[i]) continue;
    std::uint32_t slot;
    if (!freeSlots_.empty()) {
      slot = freeSlots_.back();
      freeSlots_.pop_back();
    } else {
      if (order.empty()) {
        for (std::uint32_t s = 0; s < std::uint32_t(slots_); ++s)
          if (lastNeeded_[s] != frame_) order.push_back(s);
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
          return lastNeeded_[a] != lastNeeded_[b] ? lastNeeded_[a] < lastNeeded_[b] : a < b;
        });
      }
      slot = order[scan++];  // needed_ fits the slots, so one is left
      slotOf_[tileIn_[slot]] = 0;
    }
    slotOf_[i] = std::uint16_t(slot + 1);
    tileIn_[slot] = i;
    lastNeeded_[slot] = frame_;
    const int S = slotSide();
    sendTile(*planet_, int(slot), pyramid_.key(i), 0, S - 1, 0, S - 1);
    pageTableDirty_ = true;
  }
  resident_ = std::size_t(slots_) - freeSlots_.size();
}

void HeightTileCache::sendPageTable() {
  glBindTexture(GL_TEXTURE_2D, pageTable_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (int l = 0; l <= pyramid_.coarsest; ++l) {
    const int n = pyramid_.tilesPerSide(l);
    pageScratch_.resize(std::size_t(n) * std::size_t(n));
    for (int ty = 0; ty < n; ++ty)
      for (int tx = 0; tx < n; ++tx)
        pageScratch_[std::size_t(ty) * std::size_t(n) + std::size_t(tx)] =
            slotOf_[pyramid_.index({l, tx, ty})];
    glTexSubImage2D(GL_TEXTURE_2D, l, 0, 0, n, n, GL_RED_INTEGER, GL_UNSIGNED_SHORT,
                    pageScratch_.data());
    lastUpload_ += pageScratch_.size() * sizeof(std::uint16_t);
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glBindTexture(GL_TEXTURE_2D, 0);
  pageTableDirty_ = false;
}

bool HeightTileCache::sync(const terrain::Terrain& planet, const terrain::Mesh& mesh,
                           const terrain::Camera& camera, std::string& why) {
  lastUpload_ = 0;
  grew_ = true;
  bool viewChanged = &mesh != mesh_ || mesh.generation != meshGeneration_ || !(camera == camera_);
  if (!tiles_ || planet_ != &planet || pyramid_.m != planet.grid().m()) {
    if (!allocate(planet, why)) return false;
    viewChanged = true;
  } else if (revision_ != planet.revision()) {
    if (planet.changedSince(revision_, changed_)) {
      glBindTexture(GL_TEXTURE_2D_ARRAY, tiles_);
      sendChanges(planet);
    } else {
      // Too many edits ago to know what changed: every tile is sent afresh as the view needs it.
      std::fill(slotOf_.begin(), slotOf_.end(), 0);
      std::fill(tileIn_.begin(), tileIn_.end(), kNoTile);
      freeSlots_.resize(std::size_t(slots_));
      for (int i = 0; i < slots_; ++i) freeSlots_[std::size_t(i)] = std::uint32_t(slots_ - 1 - i);
      std::fill(lastNeeded_.begin(), lastNeeded_.end(), 0);
      pageTableDirty_ = true;
      viewChanged = true;
    }
    revision_ = planet.revision();
  }
  if (viewChanged) {
    request(mesh, camera, planet.grid().side());
    mesh_ = &mesh;
    meshGeneration_ = mesh.generation;
    camera_ = camera;
  }
  if (pageTableDirty_) sendPageTable();
  if (!grew_ || glGetError() != GL_NO_ERROR) {
    release();
    why = "the height tiles could not be sent";
    return false;
  }
  return true;
}

}  // namespace ps::render
