#pragma once
// The frame benchmark's skips, each measured against doing the work in the same run (issue 9):
// frustum and horizon culling, reusing an unchanged view's tessellation, uploading only a
// changed mesh, thermal erosion on the active cells only, no edit work while the tool does not
// touch, and the overview drawn every Nth frame. Their "changes nothing visible" tests are
// tests/test_skips.cpp and the Skips tests in tests/test_render_ar_frame.cpp.
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <vector>

#include "render/planet_renderer.hpp"
#include "terrain/camera.hpp"
#include "terrain/terrain.hpp"
#include "terrain/tessellator.hpp"

namespace ps::bench {

struct SkipInputs {
  std::vector<terrain::Camera> views;  // AR views of the replay (a sample)
  terrain::TessellationSettings settings;
  cv::Mat background;         // a camera frame to draw over
  double editTouchingMs = 0;  // median edit time of the frames whose tool touched
  double editIdleMs = 0;      // median edit time of the frames whose tool did not
  int idleFrames = 0;         // frames that skipped the edit work
  double overviewMs = 0;      // median overview time when drawn
  int overviewEvery = 4;
  int repeats = 5;
};

// One JSON object: per skip, the time with the skip and without it (and what the skip saves).
// `planet` is only read; the erosion figures use a copy of it.
nlohmann::json measureSkips(render::PlanetRenderer& renderer, const terrain::Terrain& planet,
                            const SkipInputs& in);

}  // namespace ps::bench
