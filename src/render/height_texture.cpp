#include "render/height_texture.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

namespace ps::render {

HeightTexture::~HeightTexture() {
  release();
}

void HeightTexture::release() {
  if (texture_) glDeleteTextures(1, &texture_);
  texture_ = 0;
  side_ = 0;
  planet_ = nullptr;
}

void HeightTexture::sendRows(const terrain::Terrain& planet, int u0, int u1, int v0, int v1) {
  // Straight from the terrain's rows: the heights are finite and within the chart's limit
  // (terrain::Terrain enforces it on every load and edit), so nothing needs checking here.
  glPixelStorei(GL_UNPACK_ROW_LENGTH, side_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  const float* first = planet.heights().data() + std::size_t(v0) * std::size_t(side_) + u0;
  glTexSubImage2D(GL_TEXTURE_2D, 0, u0, v0, u1 - u0 + 1, v1 - v0 + 1, GL_RED, GL_FLOAT, first);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  lastUpload_ += std::size_t(u1 - u0 + 1) * std::size_t(v1 - v0 + 1) * sizeof(float);
}

bool HeightTexture::sync(const terrain::Terrain& planet, std::string& why) {
  lastUpload_ = 0;
  const int side = planet.grid().side();
  const bool same = texture_ && planet_ == &planet && side_ == side;
  if (same && revision_ == planet.revision()) return true;
  if (same && planet.changedSince(revision_, changed_)) {
    glBindTexture(GL_TEXTURE_2D, texture_);
    for (const auto& r : changed_)
      r.forEachColumnRange(planet.grid(),
                           [&](int u0, int u1) { sendRows(planet, u0, u1, r.vBegin, r.vEnd); });
    revision_ = planet.revision();
    if (glGetError() == GL_NO_ERROR) return true;
    release();
    why = "the height texture could not be updated";
    return false;
  }
  GLint maxSize = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxSize);
  if (side > maxSize) {
    release();
    why = "the grid's side " + std::to_string(side) + " is above this GPU's texture size limit " +
          std::to_string(maxSize);
    return false;
  }
  if (!texture_) glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  while (glGetError() != GL_NO_ERROR) {
  }
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, side, side, 0, GL_RED, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  if (glGetError() != GL_NO_ERROR) {
    release();
    why = "no room for a " + std::to_string(side) + "^2 float height texture";
    return false;
  }
  side_ = side;
  sendRows(planet, 0, side - 1, 0, side - 1);
  planet_ = &planet;
  revision_ = planet.revision();
  if (glGetError() != GL_NO_ERROR) {
    release();
    why = "the height texture could not be filled";
    return false;
  }
  return true;
}

}  // namespace ps::render
