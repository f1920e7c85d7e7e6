#include "app/ar_recorder.hpp"

#include <chrono>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "core/chart_factory.hpp"
#include "io/heightmap_export.hpp"
#include "render/occlusion_composite.hpp"
#include "render/projection.hpp"

namespace ps::app {

namespace {
// Frames of one touching run kept for the showcase (each AR + overview pair is ~1.6 MB at
// 640x480): a longer run is judged by its first kMaxRun frames.
constexpr std::size_t kMaxRun = 60;
}  // namespace

ArRecorder::ArRecorder(ArRecorderSettings settings) : settings_(std::move(settings)) {
  if (!settings_.frameDir.empty()) std::filesystem::create_directories(settings_.frameDir);
}

void ArRecorder::onFrame(const replay::FrameContext& f, const Eigen::Vector3d& force,
                         const Eigen::Vector3d& forceTip) {
  const bool wantSequence = !settings_.frameDir.empty() && f.frame % settings_.every == 0;
  const bool wantShowcase =
      settings_.showcase && f.touching && f.planetInCamera && run_.size() < kMaxRun;
  auto closeRun = [&] {
    if (run_.size() > bestLength_) {
      bestLength_ = run_.size();
      best_ = run_[run_.size() / 2];
    }
    run_.clear();
  };
  if (!f.touching) closeRun();
  // The hand mask learns the board's look from every frame, drawn or not, that has its own
  // board pose (replay/hand_occlusion.hpp: the live loop's and `bench frame`'s path too).
  const bool maskHands =
      settings_.handMask && replay::HandOcclusion::masks(f.scene.planet, f.planetInCamera);
  if (!wantSequence && !wantShowcase && !maskHands) return;
  const auto t0 = std::chrono::steady_clock::now();
  // The camera image as the pinhole K sees it, so the planet lands on its board
  // (tracking/undistort.hpp); made once, for the calibration the replay runs with.
  if (!undistort_) undistort_.emplace(f.calibration.forImageSize(f.image.size()));
  const cv::Mat image = undistort_->apply(f.image);
  // The planet's bounding sphere in the board's metres (FrameContext::scale).
  cv::Mat handMask = handOcclusion_.update(
      settings_.handMask, image, f.calibration.K, f.scene.planet, f.planetInCamera,
      core::boundingRadius(f.planet.chart()) / f.scale, f.toolTriangles, f.scale);
  if (!wantSequence && !wantShowcase) {
    renderMs_ +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return;
  }
  cv::Mat view, overview;
  if (f.planetInCamera) {
    const cv::Matx33d& K = f.calibration.K;
    Eigen::Matrix3d k;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
    const terrain::Camera cam = render::arCamera(f.planetInCamera->R, f.planetInCamera->t, f.scale,
                                                 k, f.image.cols, f.image.rows);
    terrain::TessellationSettings ts;
    ts.distMaxPx = settings_.distMaxPx;
    ts.triangleBudget = settings_.triangleBudget;
    // The sand TIN's region at its own detail where the TIN tool made one, joined by the
    // patch's overlap ring (docs/RENDERING.md: no background through the join without skirts).
    const auto& mesh =
        spliced_.view(tessellator_.tessellate(f.planet, cam, ts), f.patch, f.planet.chart());
    strokeTinFrames_ += f.patch ? 1 : 0;
    render::RenderStyle style;
    style.wireframe = settings_.wireframe;
    // The board's frame in the planet's: the planet frame is the board's turned by the user's
    // spin and tilt (replay/replay.hpp), when a session sidecar turned it.
    const Eigen::Matrix3d planetFromBoard = f.planetInCamera->R.transpose() * f.scene.planet.pose.R;
    style.sun = planetFromBoard * settings_.sun.normalized();
    style.boardUp = planetFromBoard.col(2);
    style.boardShadow = settings_.boardShadow;
    style.atmosphere = settings_.atmosphere;
    std::optional<render::Cursor> cursor;
    if (f.control) {
      cursor = render::Cursor{*f.control, f.toolRadius};
      // 8 N (the haptic force clamp) draws as a quarter of the planet's radius.
      if (force.allFinite() && force.norm() > 1e-6) {
        cursor->arrowFrom = forceTip;
        cursor->arrow = force * (0.25 * core::boundingRadius(f.planet.chart()) / 8.0);
      }
    }
    // The tracked tool hides the planet where it is in front of it.
    view = renderer_.renderAR(image, f.planet, mesh, cam, style, cursor, f.toolTriangles);
    if (cv::Mat occluded = render::occludeByHand(view, image, handMask, cam, f.toolTriangles);
        !occluded.empty()) {
      view = occluded;
      ++handMaskFrames_;
    }
    overview = renderer_.renderOverview(f.planet, mesh, cam, 480, 480);
  } else {
    // No planet: the camera image alone (the planet is not drawn where it is not tracked).
    if (image.channels() == 1)
      cv::cvtColor(image, view, cv::COLOR_GRAY2BGR);
    else
      view = image.clone();
  }
  renderMs_ +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (wantSequence) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", f.frame);
    io::writePngAtomically(view, settings_.frameDir / name);
    if (!overview.empty()) {
      std::snprintf(name, sizeof name, "overview_%05d.png", f.frame);
      io::writePngAtomically(overview, settings_.frameDir / name);
    }
    ++written_;
  }
  if (wantShowcase && run_.size() < kMaxRun) run_.emplace_back(view, overview);
}

bool ArRecorder::writeShowcase(const std::filesystem::path& dir) {
  if (!run_.empty()) {
    if (run_.size() > bestLength_) {
      bestLength_ = run_.size();
      best_ = run_[run_.size() / 2];
    }
    run_.clear();
  }
  if (best_.first.empty()) return false;
  io::writePngAtomically(best_.first, dir / "ar_view.png");
  if (!best_.second.empty()) io::writePngAtomically(best_.second, dir / "overview.png");
  return true;
}

}  // namespace ps::app
