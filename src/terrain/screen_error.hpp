#pragma once
#include "terrain/camera.hpp"
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::terrain {

struct ScreenErrorReport {
  double maxPx = 0;                 // largest measured screen error
  std::size_t verticesChecked = 0;  // full-resolution vertices in view
  std::size_t trianglesChecked = 0;
};

// Brute-force accuracy check of a tessellation: for every emitted triangle and every
// full-resolution grid vertex inside it (in parameter space) whose true position is in front of
// the camera and inside the image, the pixel distance between the projections of its true
// position and of the point the triangle puts it at. The mesh's triangles must be the
// tessellator's (right angle at the first corner).
ScreenErrorReport measureScreenError(const Terrain& terrain, const Camera& camera,
                                     const Mesh& mesh);

// Largest 3D distance between a full-resolution vertex and the mesh over all triangles (the
// view-independent error, for exports).
double measureTrueError(const Terrain& terrain, const Mesh& mesh);

}  // namespace ps::terrain
