#include "render/planet_renderer.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/chart_factory.hpp"
#include "io/heightmap_export.hpp"
#include "render/atmosphere_passes.hpp"
#include "render/changed_ranges.hpp"
#include "render/gl_program.hpp"
#include "render/height_tile_cache.hpp"
#include "render/mesh_shaders.hpp"
#include "render/occluder_pass.hpp"
#include "render/projection.hpp"

namespace ps::render {

namespace {

constexpr const char* kLineFragment = R"(#version 330 core
uniform vec3 lineColour;
out vec4 colour;
void main() { colour = vec4(lineColour, 1.0); }
)";

constexpr const char* kBackgroundVertex = R"(#version 330 core
out vec2 uv;
void main() {
  // One triangle covering the screen; uv (0, 0) at the image's top-left.
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  uv = vec2(0.5 * (p.x + 1.0), 0.5 * (1.0 - p.y));
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

constexpr const char* kBackgroundFragment = R"(#version 330 core
in vec2 uv;
uniform sampler2D image;
out vec4 colour;
void main() { colour = vec4(texture(image, uv).rgb, 1.0); }
)";

constexpr float kRampLow = -9000, kRampHigh = 9000;

// d position / d u and d v at grid vertex (u, v), per grid step, on the reference surface:
// central differences of the neighbours (one-sided at an edge the chart does not wrap; a
// seam's columns 0 and m, or rows 0 and m, are one point). Positions at grid vertices are table
// look-ups on every chart; positionAt between them costs trigonometry, 5 ms for a dense view's
// 25,000 vertices on every upload.
std::pair<Eigen::Vector3d, Eigen::Vector3d> gridTangents(const core::Chart& chart, int u, int v) {
  const int m = chart.grid().m();
  auto at = [&](int uu, int vv) { return chart.position(uu, vv, 0); };
  Eigen::Vector3d du;
  if (chart.wrapsU()) {
    du = 0.5 * (at(u == m ? 1 : u + 1, v) - at(u == 0 ? m - 1 : u - 1, v));
  } else {
    const int u0 = std::max(u - 1, 0), u1 = std::min(u + 1, m);
    du = (at(u1, v) - at(u0, v)) / double(u1 - u0);
  }
  if (chart.gluing().vSides == core::SideGluing::kSeam)  // the torus: rows 0 and m are one
    return {du, 0.5 * (at(u, v == m ? 1 : v + 1) - at(u, v == 0 ? m - 1 : v - 1))};
  const int v0 = std::max(v - 1, 0), v1 = std::min(v + 1, m);
  return {du, (at(u, v1) - at(u, v0)) / double(v1 - v0)};
}

}  // namespace

struct PlanetRenderer::Gl {
  GLuint meshProgram = 0, patchProgram = 0, lineProgram = 0, backgroundProgram = 0;
  GLuint meshVao = 0, positionBuffer = 0, heightBuffer = 0, indexBuffer = 0;
  GLuint gridBuffer = 0, frameBuffer = 0;                     // per vertex: (u, v); up, d/du, d/dv
  ShadowedBuffer positions, heights, indices, grids, frames;  // what the mesh buffers hold
  std::unique_ptr<HeightTileCache> heightTiles;  // holds tiles only while good to shade from
  GLuint lineVao = 0, lineBuffer = 0, emptyVao = 0;
  GLuint rampTexture = 0, imageTexture = 0;
  GLuint framebuffer = 0, colourBuffer = 0, depthBuffer = 0;
  int width = 0, height = 0;
};

PlanetRenderer::PlanetRenderer() : gl_(new Gl) {
  Gl& g = *gl_;
  g.meshProgram = linkProgram(kMeshVertex, kMeshFragment);
  g.patchProgram = linkProgram(kMeshVertex, ownSurfaceFragment().c_str());
  g.lineProgram = linkProgram(kEyeRelativeVertex, kLineFragment);
  g.backgroundProgram = linkProgram(kBackgroundVertex, kBackgroundFragment);
  glGenVertexArrays(1, &g.meshVao);
  glGenBuffers(1, &g.positionBuffer);
  glGenBuffers(1, &g.heightBuffer);
  glGenBuffers(1, &g.indexBuffer);
  glGenBuffers(1, &g.gridBuffer);
  glGenBuffers(1, &g.frameBuffer);
  glBindVertexArray(g.meshVao);
  glBindBuffer(GL_ARRAY_BUFFER, g.positionBuffer);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, g.heightBuffer);
  glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glBindBuffer(GL_ARRAY_BUFFER, g.gridBuffer);
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
  glEnableVertexAttribArray(2);
  glBindBuffer(GL_ARRAY_BUFFER, g.frameBuffer);
  for (GLuint k = 0; k < 3; ++k) {  // up, along u, along v: 9 floats per vertex
    glVertexAttribPointer(3 + k, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float),
                          reinterpret_cast<const void*>(std::uintptr_t(3 * k * sizeof(float))));
    glEnableVertexAttribArray(3 + k);
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.indexBuffer);
  makePositionArray(g.lineVao, g.lineBuffer);
  glGenVertexArrays(1, &g.emptyVao);

  // The colour ramp as a 1D texture, from the same function as the relief previews.
  std::vector<float> ramp(3 * 512);
  for (int i = 0; i < 512; ++i) {
    const cv::Vec3f bgr = io::hypsometricTint(kRampLow + (kRampHigh - kRampLow) * i / 511.0);
    for (int k = 0; k < 3; ++k) ramp[std::size_t(3 * i + k)] = bgr[2 - k] / 255.0f;
  }
  glGenTextures(1, &g.rampTexture);
  glBindTexture(GL_TEXTURE_1D, g.rampTexture);
  glTexImage1D(GL_TEXTURE_1D, 0, GL_RGB32F, 512, 0, GL_RGB, GL_FLOAT, ramp.data());
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glGenTextures(1, &g.imageTexture);
  if (glGetError() != GL_NO_ERROR) throw std::runtime_error("renderer: OpenGL setup failed");
}

PlanetRenderer::~PlanetRenderer() {
  Gl& g = *gl_;
  glDeleteProgram(g.meshProgram);
  glDeleteProgram(g.patchProgram);
  glDeleteProgram(g.lineProgram);
  glDeleteProgram(g.backgroundProgram);
  const GLuint buffers[] = {g.positionBuffer, g.heightBuffer, g.indexBuffer,
                            g.lineBuffer,     g.gridBuffer,   g.frameBuffer};
  glDeleteBuffers(6, buffers);
  const GLuint arrays[] = {g.meshVao, g.lineVao, g.emptyVao};
  glDeleteVertexArrays(3, arrays);
  const GLuint textures[] = {g.rampTexture, g.imageTexture};
  glDeleteTextures(2, textures);
  if (g.framebuffer) {
    glDeleteFramebuffers(1, &g.framebuffer);
    const GLuint rb[] = {g.colourBuffer, g.depthBuffer};
    glDeleteRenderbuffers(2, rb);
  }
  delete gl_;
}

void PlanetRenderer::target(int width, int height) {
  Gl& g = *gl_;
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw std::invalid_argument("renderer: image size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is not in 1..16384");
  if (g.framebuffer == 0 || g.width != width || g.height != height) {
    if (g.framebuffer == 0) {
      glGenFramebuffers(1, &g.framebuffer);
      glGenRenderbuffers(1, &g.colourBuffer);
      glGenRenderbuffers(1, &g.depthBuffer);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, g.colourBuffer);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, g.depthBuffer);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, g.framebuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              g.colourBuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, g.depthBuffer);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("renderer: framebuffer incomplete");
    g.width = width;
    g.height = height;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, g.framebuffer);
  glViewport(0, 0, width, height);
}

void PlanetRenderer::upload(const terrain::Terrain& planet, const terrain::Mesh& mesh) {
  stats_.uploadedThisFrame = false;
  if (uploadedMesh_ == &mesh && uploadedGeneration_ == mesh.generation) return;
  Gl& g = *gl_;
  const int side = planet.grid().side();
  const core::Chart& chart = planet.chart();
  const bool hasPatch = !mesh.patchHeights.empty();
  if (hasPatch && (mesh.patchVertexBegin + mesh.patchHeights.size() != mesh.gridIndex.size() ||
                   mesh.patchIndexBegin > mesh.indices.size()))
    throw std::invalid_argument("renderer: a mesh's patch does not match its vertices");
  std::vector<float> heights(mesh.gridIndex.size()), grids(2 * heights.size()),
      frames(9 * heights.size());
  for (std::size_t i = 0; i < heights.size(); ++i) {
    const auto gi = mesh.gridIndex[i];
    const int u = int(gi % std::uint64_t(side)), v = int(gi / std::uint64_t(side));
    // A spliced patch's vertex has its own height; its grid vertex is only the nearest one.
    const bool own = hasPatch && i >= mesh.patchVertexBegin;
    heights[i] = own ? mesh.patchHeights[i - mesh.patchVertexBegin] : planet.height(u, v);
    grids[2 * i] = float(u);
    grids[2 * i + 1] = float(v);
    // The chart's frame at the vertex, for per-pixel normals.
    const Eigen::Vector3d n = chart.up(u, v);
    const auto [du, dv] = gridTangents(chart, u, v);
    for (int k = 0; k < 3; ++k) {
      frames[9 * i + std::size_t(k)] = float(n[k]);
      frames[9 * i + 3 + std::size_t(k)] = float(du[k]);
      frames[9 * i + 6 + std::size_t(k)] = float(dv[k]);
    }
  }
  // Only the byte ranges that changed since the last upload are sent (render/changed_ranges).
  auto send = [this](ShadowedBuffer& shadow, GLenum target, GLuint buffer, const void* data,
                     std::size_t bytes) {
    glBindBuffer(target, buffer);
    return shadow.update(
        {static_cast<const std::uint8_t*>(data), bytes}, !partialUploads_,
        [&](std::size_t capacity, const void* d, std::size_t n) {
          glBufferData(target, GLsizeiptr(capacity), nullptr, GL_DYNAMIC_DRAW);
          glBufferSubData(target, 0, GLsizeiptr(n), d);
        },
        [&](std::size_t offset, std::size_t n, const void* d) {
          glBufferSubData(target, GLintptr(offset), GLsizeiptr(n), d);
        });
  };
  std::size_t sent = send(g.positions, GL_ARRAY_BUFFER, g.positionBuffer, mesh.positions.data(),
                          mesh.positions.size() * sizeof(Eigen::Vector3f));
  sent += send(g.heights, GL_ARRAY_BUFFER, g.heightBuffer, heights.data(),
               heights.size() * sizeof(float));
  sent += send(g.grids, GL_ARRAY_BUFFER, g.gridBuffer, grids.data(), grids.size() * sizeof(float));
  sent +=
      send(g.frames, GL_ARRAY_BUFFER, g.frameBuffer, frames.data(), frames.size() * sizeof(float));
  glBindVertexArray(g.meshVao);
  sent += send(g.indices, GL_ELEMENT_ARRAY_BUFFER, g.indexBuffer, mesh.indices.data(),
               mesh.indices.size() * sizeof(std::uint32_t));
  glBindVertexArray(0);
  uploadedMesh_ = &mesh;
  uploadedGeneration_ = mesh.generation;
  uploadedIndices_ = mesh.indices.size();
  uploadedPatchIndices_ = hasPatch ? mesh.patchIndexBegin : uploadedIndices_;
  ++stats_.uploads;
  stats_.uploadedBytes = sent;
  stats_.meshBytes = mesh.positions.size() * sizeof(Eigen::Vector3f) +
                     (heights.size() + grids.size() + frames.size()) * sizeof(float) +
                     mesh.indices.size() * sizeof(std::uint32_t);
  stats_.uploadedThisFrame = true;
}

void PlanetRenderer::syncHeights(const terrain::Terrain& planet, const terrain::Mesh& mesh,
                                 const terrain::Camera& camera, const RenderStyle& style) {
  Gl& g = *gl_;
  // The shader's up: a sphere's, a torus's and a cylinder's from each pixel's position.
  const core::ChartShape shape = core::shapeOf(planet.chart());
  upKind_ = planet.chart().sphereRadius() > 0      ? 1
            : shape == core::ChartShape::kTorus    ? 2
            : shape == core::ChartShape::kCylinder ? 3
                                                   : 0;
  majorRadius_ = shape == core::ChartShape::kTorus ? core::dimsOf(planet.chart()).radius : 0.0;
  stats_.heightUploadBytes = 0;
  if (style.shading != Shading::kPerPixel) return;
  if (!g.heightTiles && failedSide_ == planet.grid().side()) return;  // said once
  if (!g.heightTiles) g.heightTiles = std::make_unique<HeightTileCache>(heightCacheBudget_);
  std::string why;
  const bool ok = g.heightTiles->sync(planet, mesh, camera, why);
  stats_.heightUploadBytes = g.heightTiles->lastUploadBytes();
  stats_.heightTextureBytes = ok ? g.heightTiles->bytes() : 0;
  stats_.heightTilesHeld = ok ? g.heightTiles->residentTiles() : 0;
  stats_.heightTilesNeeded = ok ? g.heightTiles->neededTiles() : 0;
  stats_.heightLevelBias = ok ? g.heightTiles->levelBias() : 0;
  if (!ok) {
    // Facets rather than a black planet, and the reason said once.
    g.heightTiles.reset();
    failedSide_ = planet.grid().side();
    stats_.shadingNote = "per-pixel shading off (" + why + "): drawing facets";
    std::cerr << "renderer: " << stats_.shadingNote << "\n";
  }
}

void PlanetRenderer::setHeightCacheBudget(std::size_t bytes) {
  heightCacheBudget_ = bytes;
  gl_->heightTiles.reset();
  failedSide_ = 0;
  stats_.shadingNote.clear();
}

void PlanetRenderer::drawMesh(const terrain::Mesh& mesh, const terrain::Camera& camera,
                              const Eigen::Matrix4d& clip, const RenderStyle& style,
                              bool wireOnly) {
  Gl& g = *gl_;
  // The view's triangles, then a spliced patch's with the program that shades it from its own
  // surface (kMeshFragment with OWN_SURFACE: the view's program is the one it always was, so a
  // mesh without a patch draws the same bits).
  const auto draw = [&](GLuint program, std::size_t first, std::size_t count) {
    const Eigen::Vector3d offset = mesh.eye - camera.eye;
    glUseProgram(program);
    const auto m = columnMajor(clipFromEyeRelative(clip, camera.rotation, offset));
    glUniformMatrix4fv(glGetUniformLocation(program, "clipFromEyeRelative"), 1, GL_FALSE, m.data());
    glUniform3f(glGetUniformLocation(program, "offset"), float(offset.x()), float(offset.y()),
                float(offset.z()));
    const Eigen::Vector3d sun = style.sun.normalized();
    glUniform3f(glGetUniformLocation(program, "sun"), float(sun.x()), float(sun.y()),
                float(sun.z()));
    glUniform3f(glGetUniformLocation(program, "cameraPosition"), float(camera.eye.x()),
                float(camera.eye.y()), float(camera.eye.z()));
    glUniform1f(glGetUniformLocation(program, "rampLow"), kRampLow);
    glUniform1f(glGetUniformLocation(program, "rampHigh"), kRampHigh);
    glUniform1f(glGetUniformLocation(program, "contourInterval"),
                style.contours ? float(style.contourIntervalM) : 0.0f);
    glUniform1i(glGetUniformLocation(program, "wireOnly"), wireOnly ? 1 : 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_1D, g.rampTexture);
    glUniform1i(glGetUniformLocation(program, "ramp"), 0);
    const HeightTileCache* tiles = g.heightTiles.get();
    const bool perPixel = style.shading == Shading::kPerPixel && tiles && tiles->tiles() != 0;
    glUniform1i(glGetUniformLocation(program, "perPixel"), perPixel ? 1 : 0);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D_ARRAY, perPixel ? tiles->tiles() : 0);
    glUniform1i(glGetUniformLocation(program, "heightTiles"), 1);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, perPixel ? tiles->pageTable() : 0);
    glUniform1i(glGetUniformLocation(program, "pageTable"), 2);
    glActiveTexture(GL_TEXTURE0);
    if (perPixel) {
      glUniform1f(glGetUniformLocation(program, "tileCells"), float(tiles->pyramid().tileCells));
      glUniform1i(glGetUniformLocation(program, "coarsestLevel"), tiles->pyramid().coarsest);
      glUniform1f(glGetUniformLocation(program, "slotSide"), float(tiles->slotSide()));
      glUniform1i(glGetUniformLocation(program, "showTileLevels"), style.showTileLevels ? 1 : 0);
    }
    glUniform1i(glGetUniformLocation(program, "upKind"), upKind_);
    glUniform1f(glGetUniformLocation(program, "majorRadius"), float(majorRadius_));
    glUniform1f(glGetUniformLocation(program, "reliefScale"), float(style.reliefScale));
    glBindVertexArray(g.meshVao);
    if (wireOnly) {
      glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
      glEnable(GL_POLYGON_OFFSET_LINE);
      glPolygonOffset(-1, -1);
    }
    glDrawElements(GL_TRIANGLES, GLsizei(count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(first * sizeof(std::uint32_t)));
    if (wireOnly) {
      glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
      glDisable(GL_POLYGON_OFFSET_LINE);
    }
    glBindVertexArray(0);
  };
  draw(g.meshProgram, 0, uploadedPatchIndices_);
  if (uploadedPatchIndices_ < uploadedIndices_)
    draw(g.patchProgram, uploadedPatchIndices_, uploadedIndices_ - uploadedPatchIndices_);
}

void PlanetRenderer::drawLines(const std::vector<Eigen::Vector3d>& points, bool loop,
                               const terrain::Camera& camera, const Eigen::Matrix4d& clip,
                               const Eigen::Vector3f& colour, bool depthTest) {
  if (points.size() < 2) return;
  Gl& g = *gl_;
  std::vector<Eigen::Vector3f> rel;
  rel.reserve(points.size());
  for (const auto& p : points) rel.push_back((p - camera.eye).cast<float>());
  glBindVertexArray(g.lineVao);
  glBindBuffer(GL_ARRAY_BUFFER, g.lineBuffer);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(rel.size() * sizeof(Eigen::Vector3f)), rel.data(),
               GL_STREAM_DRAW);
  glUseProgram(g.lineProgram);
  const auto m = columnMajor(clipFromEyeRelative(clip, camera.rotation, Eigen::Vector3d::Zero()));
  glUniformMatrix4fv(glGetUniformLocation(g.lineProgram, "clipFromEyeRelative"), 1, GL_FALSE,
                     m.data());
  glUniform3f(glGetUniformLocation(g.lineProgram, "lineColour"), colour.x(), colour.y(),
              colour.z());
  if (!depthTest) glDisable(GL_DEPTH_TEST);
  glDrawArrays(loop ? GL_LINE_LOOP : GL_LINES, 0, GLsizei(rel.size()));
  glEnable(GL_DEPTH_TEST);
  glBindVertexArray(0);
}

cv::Mat PlanetRenderer::readBack() const {
  const Gl& g = *gl_;
  cv::Mat rgba(g.height, g.width, CV_8UC4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, g.width, g.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data);
  cv::Mat bgr, flipped;
  cv::cvtColor(rgba, bgr, cv::COLOR_RGBA2BGR);
  cv::flip(bgr, flipped, 0);  // GL's row 0 is the bottom
  return flipped;
}

cv::Mat PlanetRenderer::readDepth() const {
  const Gl& g = *gl_;
  cv::Mat depth(g.height, g.width, CV_32F), flipped;
  glBindFramebuffer(GL_FRAMEBUFFER, g.framebuffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, g.width, g.height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data);
  cv::flip(depth, flipped, 0);
  return flipped;
}

void PlanetRenderer::present(int x, int y, int width, int height) const {
  const Gl& g = *gl_;
  if (g.framebuffer == 0 || width <= 0 || height <= 0) return;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, g.framebuffer);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, g.width, g.height, x, y, x + width, y + height, GL_COLOR_BUFFER_BIT,
                    (width == g.width && height == g.height) ? GL_NEAREST : GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void PlanetRenderer::drawBoardShadowAndRim(const terrain::Camera& camera, double R,
                                           const RenderStyle& style) {
  if (!(style.boardShadow || style.atmosphere) || !(R > 0)) return;
  if (!atmosphere_) atmosphere_ = std::make_unique<AtmospherePasses>();
  const Eigen::Vector3d sun = style.sun.normalized(), up = style.boardUp.normalized();
  if (style.boardShadow) atmosphere_->drawBoardShadow(camera, R, sun, up);
  if (style.atmosphere) atmosphere_->drawRim(camera, R, sun);
}

namespace {
// Back faces are culled, but a cylinder's: through its open ends its inside is seen.
void cullBackFaces(const terrain::Terrain& planet) {
  if (core::shapeOf(planet.chart()) == core::ChartShape::kCylinder)
    glDisable(GL_CULL_FACE);
  else
    glEnable(GL_CULL_FACE);
}
}  // namespace

cv::Mat PlanetRenderer::renderAR(const cv::Mat& background, const terrain::Terrain& planet,
                                 const terrain::Mesh& mesh, const terrain::Camera& camera,
                                 const RenderStyle& style, const std::optional<Cursor>& cursor,
                                 std::span<const Eigen::Vector3d> occluders) {
  camera.validate();
  if (!background.empty() && (background.cols != camera.width || background.rows != camera.height))
    throw std::invalid_argument("renderer: background is " + std::to_string(background.cols) + "x" +
                                std::to_string(background.rows) + ", the camera " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  Gl& g = *gl_;
  target(camera.width, camera.height);
  upload(planet, mesh);
  syncHeights(planet, mesh, camera, style);
  glClearColor(0, 0, 0, 1);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (!background.empty()) {
    cv::Mat rgb;
    if (background.channels() == 1)
      cv::cvtColor(background, rgb, cv::COLOR_GRAY2RGB);
    else
      cv::cvtColor(background, rgb, cv::COLOR_BGR2RGB);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, g.imageTexture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, rgb.cols, rgb.rows, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 rgb.data);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glUseProgram(g.backgroundProgram);
    glUniform1i(glGetUniformLocation(g.backgroundProgram, "image"), 0);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(g.emptyVao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
  }
  drawBoardShadowAndRim(camera, planet.chart().sphereRadius(), style);
  const DepthRange depth = depthRangeFor(camera, planet);
  const Eigen::Matrix4d clip = clipFromCamera(camera, depth.nearZ, depth.farZ);
  // The tool's depth (and the camera image over the shadow and rim where it stands), before the
  // planet: the planet is hidden where the tool is nearer.
  if (occluders.size() >= 3) {
    if (!occluders_) occluders_ = std::make_unique<OccluderPass>();
    occluders_->draw(occluders, camera, clip, background.empty() ? 0 : g.imageTexture);
  }
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  cullBackFaces(planet);
  glCullFace(GL_BACK);
  // Triangles are CCW seen from outside; the projection negates y (OpenCV's rows go down, GL's
  // up), which keeps that winding in GL's window.
  glFrontFace(GL_CCW);
  drawMesh(mesh, camera, clip, style, false);
  if (style.wireframe) drawMesh(mesh, camera, clip, style, true);
  glDisable(GL_CULL_FACE);
  if (cursor) drawCursor(planet, *cursor, camera, clip);
  return readBack();
}

cv::Mat PlanetRenderer::renderOverview(const terrain::Terrain& planet, const terrain::Mesh& arMesh,
                                       const terrain::Camera& arCamera, int width, int height) {
  // The planet's bounding sphere: a sphere's radius, a torus's or a cylinder's sphere about
  // its centre (core::boundingRadius).
  const double R = core::boundingRadius(planet.chart());
  if (!(R > 0)) throw std::invalid_argument("renderer: the overview needs a planet with a centre");
  // From 3.2 radii away, 60 degrees around from the AR
  // camera's side (about the axis across both the AR direction and the pole), so that the AR
  // camera's frustum crosses the picture.
  Eigen::Vector3d side = arCamera.eye;
  if (side.norm() < 1e-9 * R) side = Eigen::Vector3d::UnitX();
  side.normalize();
  Eigen::Vector3d axis = side.cross(Eigen::Vector3d::UnitZ());
  if (axis.norm() < 1e-6) axis = side.unitOrthogonal();
  const Eigen::Vector3d dir =
      Eigen::AngleAxisd(std::numbers::pi / 3, axis.normalized()).toRotationMatrix() * side;
  const terrain::Camera over =
      terrain::Camera::lookAt(3.2 * R * dir, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(),
                              width, height, 40 * std::numbers::pi / 180);
  target(width, height);
  upload(planet, arMesh);
  glClearColor(0.03f, 0.04f, 0.08f, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  cullBackFaces(planet);
  glFrontFace(GL_CCW);
  const DepthRange depth = depthRangeFor(over, planet);
  const Eigen::Matrix4d clip = clipFromCamera(over, depth.nearZ, depth.farZ);
  RenderStyle style;
  style.wireframe = true;
  style.shading = Shading::kFaceted;  // the overview shows the tessellation
  drawMesh(arMesh, over, clip, style, false);
  drawMesh(arMesh, over, clip, style, true);
  glDisable(GL_CULL_FACE);
  // The AR camera's frustum: rays through the image corners, out to the planet's far side.
  const double reach = arCamera.eye.norm() + R;
  std::vector<Eigen::Vector3d> lines;
  const Eigen::Matrix3d Rt = arCamera.rotation.transpose();
  const double W = arCamera.width - 1, H = arCamera.height - 1;
  std::array<Eigen::Vector3d, 4> corners;
  const std::array<Eigen::Vector2d, 4> px = {Eigen::Vector2d(0, 0), Eigen::Vector2d(W, 0),
                                             Eigen::Vector2d(W, H), Eigen::Vector2d(0, H)};
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d ray((px[i].x() - arCamera.cx) / arCamera.fx,
                              (px[i].y() - arCamera.cy) / arCamera.fy, 1.0);
    corners[i] = arCamera.eye + Rt * ray.normalized() * reach;
    lines.push_back(arCamera.eye);
    lines.push_back(corners[i]);
  }
  for (std::size_t i = 0; i < 4; ++i) {
    lines.push_back(corners[i]);
    lines.push_back(corners[(i + 1) % 4]);
  }
  // The optical axis: where the AR camera looks (its frustum is usually far wider than the
  // planet, which fills a small part of a webcam image).
  lines.push_back(arCamera.eye);
  lines.push_back(arCamera.eye + Rt.col(2) * reach);
  drawLines(lines, false, over, clip, {1.0f, 0.85f, 0.1f}, true);
  return readBack();
}

}  // namespace ps::render
