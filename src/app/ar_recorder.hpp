#pragma once
// Watches a replay (replay::FrameHook) and renders what a user would have seen: the AR view
// (camera image, planet on its marker, cursor) and the overview. Writes every `every`-th frame
// to DIR/ar/frame_NNNNN.png (and DIR/ar/overview_NNNNN.png) when asked, and keeps the frame in
// the middle of the longest touching run as the showcase (ar_view.png, overview.png).
#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>

#include <optional>

#include "render/egl_context.hpp"
#include "render/planet_renderer.hpp"
#include "replay/hand_occlusion.hpp"
#include "replay/replay.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/undistort.hpp"

namespace ps::app {

struct ArRecorderSettings {
  std::filesystem::path frameDir;  // empty: no frame sequence
  int every = 1;
  bool showcase = true;
  double distMaxPx = 1.0;
  std::size_t triangleBudget = 70000;
  bool wireframe = false;
  // The sun in the board's frame (x, y on the board the planet stands on, z up from it), the
  // planet's shadow on the board and the atmosphere rim (render/atmosphere_passes.hpp).
  Eigen::Vector3d sun = Eigen::Vector3d(1, 1, 1).normalized();
  bool boardShadow = true, atmosphere = true;
  // The camera image shown over the planet where something is in front of it (a hand:
  // replay/hand_occlusion.hpp, learned from every frame; render/occlusion_composite.hpp).
  bool handMask = true;
};

class ArRecorder {
 public:
  // Throws std::runtime_error when no headless OpenGL context can be made.
  explicit ArRecorder(ArRecorderSettings settings);
  // `force`: the haptic force of the frame (N, planet-frame direction) at `forceTip` (planet
  // metres), drawn as an arrow; zero for none.
  void onFrame(const replay::FrameContext& frame,
               const Eigen::Vector3d& force = Eigen::Vector3d::Zero(),
               const Eigen::Vector3d& forceTip = Eigen::Vector3d::Zero());
  // Writes ar_view.png and overview.png into `dir`; false when no frame touched.
  bool writeShowcase(const std::filesystem::path& dir);
  int framesWritten() const { return written_; }
  std::string renderer() const { return context_.renderer(); }
  double renderMsTotal() const { return renderMs_; }
  // Frames rendered with the sand TIN's region spliced in (FrameContext::patch).
  int strokeTinFrames() const { return strokeTinFrames_; }
  int handMaskFrames() const { return handMaskFrames_; }

 private:
  ArRecorderSettings settings_;
  render::EglContext context_;
  render::PlanetRenderer renderer_;
  terrain::Tessellator tessellator_;
  terrain::SplicedView spliced_;  // the view with the sand TIN's region (FrameContext::patch)
  std::optional<tracking::FrameUndistorter> undistort_;
  replay::HandOcclusion handOcclusion_;
  // Frames whose AR view showed the camera image over part of the planet (a hand in front).
  int handMaskFrames_ = 0;
  int written_ = 0;
  int strokeTinFrames_ = 0;
  double renderMs_ = 0;
  // The current touching run's frames and the best (longest) run's middle frame.
  std::vector<std::pair<cv::Mat, cv::Mat>> run_;
  std::pair<cv::Mat, cv::Mat> best_;
  std::size_t bestLength_ = 0;
};

}  // namespace ps::app
