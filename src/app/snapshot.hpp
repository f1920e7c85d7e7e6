#pragma once
#include <opencv2/core.hpp>

#include "terrain/camera.hpp"
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::app {

// A software picture of a tessellated view (painter's algorithm, Lambert shading, hypsometric
// tint, optional wireframe) for previews and README images where no GL context is wanted.
cv::Mat renderSnapshot(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
                       const terrain::Camera& camera, bool wireframe);

}  // namespace ps::app
