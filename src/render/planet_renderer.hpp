#pragma once
// The planet in OpenGL (3.3 core), one code path for the headless EGL context and a window:
//   * AR view: the camera image as background, the tessellated planet over it with the
//     calibrated intrinsics (render/projection.hpp), depth-tested, lit, hypsometric colours,
//     optional contour lines and wireframe, and a cursor (the control vertex and a ring of
//     radius r_d on the surface);
//   * overview: the whole planet from outside with the AR view's mesh (its tessellation) and
//     the AR camera's frustum.
// Vertices are uploaded relative to the mesh's eye (terrain::Mesh), so float keeps full
// precision near the camera: no jitter 1 m above a 6,372 km planet. A mesh is uploaded again
// only when it changed (the tessellator returns the same mesh for an unchanged view and
// terrain), and then only its changed 4 KiB chunks (render/changed_ranges.hpp).
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string>

#include "core/grid.hpp"
#include "terrain/camera.hpp"
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::render {

// How a pixel of the planet takes its colour (render/mesh_shaders.hpp): from the
// full-resolution heights (per pixel) or from its triangle (faceted: the tessellation shows).
enum class Shading { kPerPixel, kFaceted };

struct RenderStyle {
  Shading shading = Shading::kPerPixel;
  double reliefScale = 8;  // vertical exaggeration of per-pixel shading, as the previews'
  bool wireframe = false;
  bool contours = false;
  double contourIntervalM = 1000;
  Eigen::Vector3d sun = Eigen::Vector3d(1, 1, 1).normalized();  // planet frame, toward the sun
  // Per-pixel shading's diagnostic: each pixel coloured by the pyramid level it reads (green
  // full resolution to blue coarsest), red where that level is coarser than its footprint asks
  // (the tile it wanted is not held).
  bool showTileLevels = false;
  // The AR view only, on a spherical planet (render/atmosphere_passes.hpp): the planet's soft
  // shadow on the board it stands on (the plane p . boardUp = -R, boardUp a unit vector in the
  // planet frame: +z unless the planet is turned on its board) and a thin atmosphere rim.
  bool boardShadow = false;
  bool atmosphere = false;
  Eigen::Vector3d boardUp = Eigen::Vector3d::UnitZ();
};

// The edit cursor: the control vertex and the deformation radius r_d (planet metres).
struct Cursor {
  core::GridPoint control;
  double radius = 0;
  // The haptic force on the tool, as an arrow from the tool tip (planet frame, planet metres);
  // a zero vector draws none.
  Eigen::Vector3d arrowFrom = Eigen::Vector3d::Zero();
  Eigen::Vector3d arrow = Eigen::Vector3d::Zero();
};

struct RenderStats {
  std::size_t uploads = 0;        // mesh uploads so far
  std::size_t uploadedBytes = 0;  // bytes sent by the last upload (only its changed ranges)
  std::size_t meshBytes = 0;      // bytes of the last uploaded mesh (what a full upload sends)
  bool uploadedThisFrame = false;
  std::size_t heightTextureBytes = 0;  // GPU memory of the height tile cache (0: none)
  std::size_t heightUploadBytes = 0;   // height texels (and page table) sent by the last frame
  std::size_t heightTilesHeld = 0;     // tiles of the height pyramid the cache holds
  std::size_t heightTilesNeeded = 0;   // of which the last view needed
  int heightLevelBias = 0;             // levels made coarser to fit the cache (0: none)
  std::string shadingNote;             // why per-pixel shading is off, when it is
};

class AtmospherePasses;
class OccluderPass;

class PlanetRenderer {
 public:
  // Needs a current OpenGL 3.3 context (render/egl_context.hpp or a window's). Throws
  // std::runtime_error with the compiler log if a shader does not build.
  PlanetRenderer();
  ~PlanetRenderer();
  PlanetRenderer(const PlanetRenderer&) = delete;
  PlanetRenderer& operator=(const PlanetRenderer&) = delete;

  // The AR frame at the camera's size: `background` (BGR or grey, the camera's size; empty for
  // a black background) with the planet drawn over it. Returns BGR 8-bit. `occluders`: what
  // stands in front of the planet (the tracked tool's triangles, 3 points each, planet frame,
  // planet metres; tracking/tool_shape.hpp): the planet is hidden where they are nearer the
  // camera, and the camera image shows there (render/occluder_pass.hpp).
  cv::Mat renderAR(const cv::Mat& background, const terrain::Terrain& planet,
                   const terrain::Mesh& mesh, const terrain::Camera& camera,
                   const RenderStyle& style, const std::optional<Cursor>& cursor = std::nullopt,
                   std::span<const Eigen::Vector3d> occluders = {});

  // The overview at width x height: the planet seen from outside (3.2 radii away, 60 degrees
  // round from the AR camera) with `arMesh` in wireframe, the AR camera's frustum and its axis.
  cv::Mat renderOverview(const terrain::Terrain& planet, const terrain::Mesh& arMesh,
                         const terrain::Camera& arCamera, int width, int height);

  // Copies the last rendered image (renderAR or renderOverview) into framebuffer 0 (a window's
  // back buffer) at x, y, width, height (GL window coordinates: origin at the bottom left),
  // scaled linearly. A blit on the
  // GPU: the window shows the very pixels the headless path reads back, with no second
  // upload of the image (the live app, app/cmd_live.cpp). Both the renderer's framebuffer and
  // a window's keep GL's bottom-up rows, so no flip is needed. Leaves framebuffer 0 bound.
  void present(int x, int y, int width, int height) const;

  // The last rendered image's window depth (CV_32F, top row first as the images: 1 where
  // nothing was drawn, else [0, 1] through clipFromCamera's near and far planes): what tests
  // compare with a surface's own depth.
  cv::Mat readDepth() const;

  const RenderStats& stats() const { return stats_; }
  // On (the default), a changed mesh sends only its changed byte ranges; off sends it whole
  // (the baseline the frame benchmark and the tests compare with).
  void setPartialUploads(bool on) { partialUploads_ = on; }
  // GPU memory for per-pixel shading's height tiles (render/height_tile_cache.hpp; 64 MiB by
  // default, whatever the grid). A budget too small for the view's coarsest levels turns
  // per-pixel shading off with a note (stats().shadingNote), and facets are drawn.
  void setHeightCacheBudget(std::size_t bytes);

 private:
  struct Gl;
  void upload(const terrain::Terrain& planet, const terrain::Mesh& mesh);
  void syncHeights(const terrain::Terrain& planet, const terrain::Mesh& mesh,
                   const terrain::Camera& camera, const RenderStyle& style);
  void target(int width, int height);
  void drawMesh(const terrain::Mesh& mesh, const terrain::Camera& camera,
                const Eigen::Matrix4d& clip, const RenderStyle& style, bool wireOnly);
  void drawLines(const std::vector<Eigen::Vector3d>& planetPoints, bool loop,
                 const terrain::Camera& camera, const Eigen::Matrix4d& clip,
                 const Eigen::Vector3f& colour, bool depthTest);
  cv::Mat readBack() const;
  // The cursor (planet_renderer_cursor.cpp): on a sphere a ring at geodesic distance r_d, a
  // cross and the force arrow; else drawSurfaceCursor's.
  void drawCursor(const terrain::Terrain& planet, const Cursor& cursor,
                  const terrain::Camera& camera, const Eigen::Matrix4d& clip);
  // The cursor on a surface that is no sphere (a torus, a cylinder): a ring of the tool's
  // radius about the control vertex in its tangent plane and a cross, each point laid back onto
  // the surface through the chart's inverse and lifted as a sphere's ring is.
  void drawSurfaceCursor(const terrain::Terrain& planet, const Cursor& cursor,
                         const terrain::Camera& camera, const Eigen::Matrix4d& clip);
  // The board shadow and the atmosphere rim, when `style` asks for them (after the background,
  // before the planet).
  void drawBoardShadowAndRim(const terrain::Camera& camera, double R, const RenderStyle& style);

  Gl* gl_;
  RenderStats stats_;
  const terrain::Mesh* uploadedMesh_ = nullptr;  // identity of what the buffers hold
  std::uint64_t uploadedGeneration_ = 0;
  std::size_t uploadedIndices_ = 0;
  std::size_t uploadedPatchIndices_ = 0;  // where a spliced patch's triangles start (else all)
  bool partialUploads_ = true;
  int upKind_ = 0;  // the mesh shader's (mesh_shaders.hpp)
  double majorRadius_ = 0;
  std::size_t heightCacheBudget_ = std::size_t(64) << 20;
  int failedSide_ = 0;  // a grid side the height tile cache could not hold
  std::unique_ptr<AtmospherePasses> atmosphere_;  // made at the first frame that asks for it
  std::unique_ptr<OccluderPass> occluders_;       // likewise
};

}  // namespace ps::render
