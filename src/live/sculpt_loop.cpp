#include "live/sculpt_loop.hpp"

#define GLFW_INCLUDE_NONE  // events only; the window is live/gl_window's
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>

#include "core/chart_factory.hpp"
#include "core/input_error.hpp"
#include "haptics/device.hpp"
#include "haptics/force_path.hpp"
#include "io/planet_file.hpp"
#include "io/stroke_journal.hpp"
#include "live/panel.hpp"
#include "live/panel_mapping.hpp"
#include "live/window_layout.hpp"
#include "render/occlusion_composite.hpp"
#include "render/projection.hpp"
#include "replay/hand_occlusion.hpp"
#include "replay/session_timeline.hpp"
#include "sand/displacement.hpp"
#include "session/frame_recorder.hpp"
#include "session/planet_export.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/tessellator.hpp"
#include "tracking/undistort.hpp"

namespace ps::live {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

class SculptLoop {
 public:
  SculptLoop(Shell& shell, const tracking::CameraCalibration& calib, const Eigen::Matrix3d& K,
             const replay::ReplayOptions& options, terrain::Terrain& planet, bool recovered,
             const session::SessionFiles& files)
      : shell_(shell),
        settings_(shell.settings),
        result_(shell.result),
        calib_(calib),
        K_(K),
        planet_(planet),
        recovered_(recovered),
        savePath_(files.planet),
        stepper_(calib, planet, options),
        // The planet on disk: saved now, then autosaved; every stroke, undo and redo journaled.
        store_(planet, files, {settings_.autosaveSeconds, true}, now()),
        // Every settings change, undo and redo goes through `settingsControl_`, which also writes
        // it to the recording's sidecar (replay/session_timeline.hpp): a replay applies them the
        // same way.
        settingsControl_(stepper_),
        startCrc_(io::heightsChecksum(planet.heights())),
        // With no planet pose yet: the camera image alone (an empty mesh, any valid camera).
        placeholder_(render::arCamera(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1),
                                      stepper_.scale(), K, shell.camera.width,
                                      shell.camera.height)),
        panel_(panelFrom(settings_)),
        applied_(panel_) {
    stepper_.pipeline().journal().setListener(&store_);
    status_.savePath = savePath_.string();
    if (!settings_.record.empty()) startRecording(settings_.record);
  }
  ~SculptLoop() {
    if (haptic_) haptic_->stopLoop();
    stepper_.pipeline().journal().setListener(nullptr);
  }
  SculptLoop(const SculptLoop&) = delete;
  SculptLoop& operator=(const SculptLoop&) = delete;

  // Until the window closes, Ctrl-C or the frame limit; then the planet is saved. Whatever
  // goes wrong, the planet is saved before the error goes on.
  void run() {
    try {
      startHaptics();
      std::cerr << "live: window open (" << glRendererName()
                << "); close it, press Esc or Ctrl-C to save and quit" << std::endl;
      while (shell_.running()) frame();
      finish();
    } catch (...) {
      try {
        recorder_.stop();
        save();
        std::cerr << "live: the planet was saved before the error\n";
      } catch (...) {
      }
      throw;
    }
  }

 private:
  double now() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  void frame() {
    const auto t0 = std::chrono::steady_clock::now();
    glfwPollEvents();
    status_.trackMs = status_.editMs = 0;
    if (shell_.input.read(frame_))
      track(frame_);
    else
      noFrame();
    followForces();
    keepFiles();
    const cv::Size fb = drawView();
    const PanelActions actions = drawInterface(fb);
    applySettings();
    applyActions(actions);
    const double ms = msSince(t0);
    smoothedMs_ = smoothedMs_ == 0 ? ms : 0.9 * smoothedMs_ + 0.1 * ms;
    status_.frameMs = smoothedMs_;
    status_.fps = smoothedMs_ > 0 ? 1000 / smoothedMs_ : 0;
    ++result_.frames;
  }

  // A camera frame: recorded (when recording), tracked and sculpted with; the tool's tip goes
  // to the haptic device.
  void track(const cv::Mat& frame) {
    // Shown as the pinhole K sees it, under the planet drawn with that K
    // (tracking/undistort.hpp); tracked and recorded as the camera gave it.
    shell_.image = undistort_.apply(frame);
    if (recorder_.recording()) try {
        if (sidecarPending_) openSidecar();  // no recording without its sidecar
        recorder_.write(frame);
        timeline_.frameRecorded(shell_.input.time());
      } catch (const std::exception& e) {
        note_ = std::string("recording stopped: ") + e.what();
        stopRecording();
      }
    const auto r = stepper_.step(frame, shell_.input.index(), shell_.input.time());
    if (!r.settled.empty()) store_.recordRegion(r.settled);
    status_.trackMs = r.times.detectMs + r.times.trackMs;
    status_.editMs = r.times.editMs;
    pose_ = r.planetInCamera;
    maskHands(r);
    toolTriangles_ = r.toolTriangles;  // the tool in front of the planet hides it
    controlVertex_ = r.control;
    status_.touching = r.touching;
    if (haptic_) {
      const double t = haptic_->loop()->now();
      if (r.scene.tipValid)
        hapticDevice_->push(r.scene.tipPlanet, t);
      else
        hapticDevice_->push(Eigen::Vector3d::Constant(std::nan("")), t);
    }
    status_.planetState = tracking::toString(r.scene.planet.state);
    status_.toolState = tracking::toString(r.scene.tool.state);
  }

  // Where a hand is in front of the planet (replay/hand_occlusion.hpp, the AR recorder's and
  // `bench frame`'s path too): the board's look learned from every tracked frame, the mask kept
  // for drawView.
  void maskHands(const replay::StepResult& r) {
    cv::Matx33d K;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) K(i, j) = K_(i, j);
    const double radius = core::boundingRadius(planet_.chart()) / stepper_.scale();
    handMask_ = handOcclusion_.update(panel_.handMask, shell_.image, K, r.scene.planet, pose_,
                                      radius, r.toolTriangles, stepper_.scale());
    status_.trackMs += handOcclusion_.lastMs();
  }

  // No frame (camera lost, video ended): the tool is not seen, so no stroke goes on; the last
  // image and the planet on it stay.
  void noFrame() {
    stepper_.endStroke();
    status_.touching = false;
    controlVertex_.reset();
    toolTriangles_.clear();
  }

  void followForces() {
    if (!haptic_) return;
    haptic_->setSurface(stepper_.viewPatch());
    const auto forces = haptic_->editorFrame();
    if (forces.last) lastForce_ = forces.last;
    status_.forceN = lastForce_ && lastForce_->touching ? lastForce_->force.norm() : 0.0;
    const double elapsed = haptic_->loop()->now();
    status_.hapticHz = elapsed > 0 ? double(haptic_->loop()->stats().ticks) / elapsed : 0.0;
  }

  // Exports that finished, the autosave between strokes, and what the panel says about files.
  void keepFiles() {
    if (const auto x = exporter_.poll()) reportExport(*x);
    // Saves run on the store's writer thread: started here, reported when done.
    store_.tick(now(), stepper_.pipeline().inStroke());
    if (const std::uint64_t done = store_.savesDone(); done > savesSeen_) {
      result_.autosaves += int(done - savesSeen_);
      savesSeen_ = done;
      char ms[48];
      std::snprintf(ms, sizeof ms, " (%.0f ms, in the background)", store_.lastSaveMs());
      note_ = "saved " + savePath_.string() + ms;
      std::cerr << "live: " << note_ << "\n";
    }
    if (!store_.error().empty()) note_ = store_.error();
    if (!timeline_.error().empty()) note_ = timeline_.error();
    status_.autosaveInS =
        settings_.autosaveSeconds > 0
            ? std::max(0.0, store_.lastSaveTime() + settings_.autosaveSeconds - now())
            : -1.0;
    status_.journalRecords = store_.recordsSinceSave();
    status_.recordPath = recorder_.recording() ? recorder_.path().string() : "";
    status_.recordedFrames = recorder_.frames();
    status_.message = shell_.input.status();
    if (!note_.empty()) status_.message += (status_.message.empty() ? "" : "\n") + note_;
  }

  // The AR view (and every Nth frame the overview), through the renderer's framebuffer,
  // blitted into the window.
  cv::Size drawView() {
    auto t1 = std::chrono::steady_clock::now();
    terrain::TessellationSettings ts;
    ts.distMaxPx = panel_.distMaxPx;
    ts.triangleBudget = std::size_t(std::max(1000, panel_.triangleBudget));
    render::RenderStyle style;
    style.wireframe = panel_.wireframe;
    style.shading = panel_.facets ? render::Shading::kFaceted : render::Shading::kPerPixel;
    const double lon = panel_.sunLonDeg * M_PI / 180, lat = panel_.sunLatDeg * M_PI / 180;
    style.sun = {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
    style.contours = panel_.contours;
    // The board in the planet frame: the planet frame is the board's turned by the panel's spin
    // and tilt (replay/replay.hpp, FrameStepper::setUserRotation).
    style.boardUp = stepper_.userRotation().row(2).transpose();
    style.boardShadow = panel_.boardShadow;
    style.atmosphere = panel_.atmosphere;
    std::optional<terrain::Camera> cam;
    const terrain::Mesh* mesh = &empty_;
    if (pose_) {
      cam = render::arCamera(pose_->R, pose_->t, stepper_.scale(), K_, shell_.camera.width,
                             shell_.camera.height);
      mesh = &tessellator_.tessellate(planet_, *cam, ts);
      status_.reused = tessellator_.stats().reused;
      // The sand TIN's region at its own detail (replay's ArRecorder does the same).
      mesh = &spliced_.view(*mesh, stepper_.viewPatch(), planet_.chart());
      status_.triangles = mesh->triangleCount();
    } else {
      status_.triangles = 0;
      status_.reused = false;
    }
    status_.tessellateMs = msSince(t1);
    t1 = std::chrono::steady_clock::now();
    // The overview first: it uses the renderer's framebuffer too, and the AR view must be the
    // last image there when it is presented (and framebuffer 0 bound for the panel).
    if (cam && panel_.showOverview && result_.frames % settings_.overviewEvery == 0)
      overview_.update(shell_.renderer.renderOverview(planet_, *mesh, *cam, 256, 256));
    std::optional<render::Cursor> cursor;
    if (controlVertex_) {
      cursor = render::Cursor{*controlVertex_, stepper_.toolRadius()};
      // 8 N (the force clamp) draws as a quarter of the planet's radius.
      if (lastForce_ && lastForce_->touching && lastForce_->tipPlanet.allFinite()) {
        cursor->arrowFrom = lastForce_->tipPlanet;
        cursor->arrow = lastForce_->force * (0.25 * core::boundingRadius(planet_.chart()) / 8.0);
      }
    }
    const cv::Size fb = shell_.present(planet_, *mesh, cam ? *cam : placeholder_, style, cursor,
                                       cam ? std::span<const Eigen::Vector3d>(toolTriangles_)
                                           : std::span<const Eigen::Vector3d>());
    // A hand in front of the planet: the camera image over it, drawn over the blitted view by
    // drawInterface (render/occlusion_composite.hpp; the renderer's framebuffer is left as it is).
    const cv::Mat handView =
        cam ? render::occludeByHand(shell_.lastView, shell_.image, handMask_, *cam, toolTriangles_)
            : cv::Mat();
    showHandView_ = !handView.empty();
    if (showHandView_) handView_.update(handView);
    status_.renderMs = msSince(t1);
    return fb;
  }

  // The panel, the overview inset and the input's message over the view; returns what the
  // user (or the script) asked for.
  PanelActions drawInterface(cv::Size fb) {
    shell_.imgui.newFrame();
    if (showHandView_ && handView_.valid()) {
      const ImVec2 display = ImGui::GetIO().DisplaySize;
      const cv::Rect v = arViewRect(fb, int(display.x), shell_.camera);
      const float s = display.x / float(std::max(1, fb.width));  // framebuffer px -> display
      ImGui::GetBackgroundDrawList()->AddImage(handView_.imgui(), ImVec2(v.x * s, v.y * s),
                                               ImVec2((v.x + v.width) * s, (v.y + v.height) * s));
    }
    PanelActions actions;
    applyShortcuts(panel_, actions);
    status_.undoCount = stepper_.pipeline().journal().undoCount();
    status_.redoCount = stepper_.pipeline().journal().redoCount();
    const float panelBottom = live::drawControlPanel(panel_, actions, status_);
    applyScript(settings_.script, result_.frames, actions, panel_);
    if (actions.crash) std::raise(SIGKILL);     // a scripted crash: nothing saved, nothing flushed
    if (actions.interrupt) std::raise(SIGINT);  // handled as a Ctrl-C from outside is
    if (panel_.showOverview && overview_.valid()) {
      const ImVec2 display = ImGui::GetIO().DisplaySize;
      // At the foot of the panel's column, beside the AR view.
      ImGui::SetNextWindowPos(ImVec2(display.x - kSideColumnWidth / 2.0f, display.y - 8),
                              ImGuiCond_Always, ImVec2(0.5f, 1));
      ImGui::SetNextWindowBgAlpha(0.6f);
      ImGui::Begin("overview", nullptr,
                   ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoDecoration);
      // As large as the column's room under the panel allows (the panel grows with a message).
      const float side = std::clamp(display.y - panelBottom - 24, 96.0f, float(kOverviewSide));
      ImGui::Image(overview_.imgui(), ImVec2(side, side));
      ImGui::End();
    }
    if (!shell_.input.status().empty()) {
      ImDrawList* draw = ImGui::GetForegroundDrawList();
      const ImVec2 display = ImGui::GetIO().DisplaySize;
      draw->AddText(nullptr, 22, ImVec2(16, display.y * 0.5f), IM_COL32(255, 90, 60, 255),
                    shell_.input.status().c_str());
    }
    shell_.finish(fb);
    return actions;
  }

  // The panel's tool and planet settings, when they changed (a refused value is kept out; the
  // rest applies). A new planet scale restarts the force path.
  void applySettings() {
    if (!sculptingChanged(panel_, applied_)) return;
    const double scale = stepper_.scale();
    try {
      settingsControl_.apply(panelTarget(panel_, applied_, settingsControl_.settings()));
      applied_ = panel_;
    } catch (const core::InputError& e) {
      note_ = e.what();
    }
    if (stepper_.scale() != scale) startHaptics();
  }

  void applyActions(const PanelActions& actions) {
    try {
      if (actions.undo) {
        settingsControl_.undo();
        note_ = "undone";
      }
      if (actions.redo) {
        settingsControl_.redo();
        note_ = "redone";
      }
    } catch (const core::InputError& e) {
      note_ = e.what();
    }
    if (actions.save) {
      stepper_.endStroke();
      store_.requestSave();  // at the next frame, in the background
      note_ = "saving " + savePath_.string() + " ...";
    }
    if (actions.exportPlanet) {
      try {
        exporter_.start(planet_, settings_.out / "exports");  // a copy, written by a thread
        note_ = "exporting to " + (settings_.out / "exports").string() + " ...";
        status_.exportPath = "exporting ...";
      } catch (const std::exception& e) {
        note_ = std::string("not exported: ") + e.what();
      }
    }
    if (actions.record) {
      try {
        if (recorder_.recording()) {
          note_ = stopRecording();
        } else {
          startRecording(session::nextRecordingPath(settings_.out));
          note_ = "recording to " + recorder_.path().string();
        }
      } catch (const std::exception& e) {
        note_ = std::string("recording: ") + e.what();
      }
    }
    if (actions.quit) shell_.window.requestClose();
  }

  // The window closed: the stroke ended, the recording and a running export finished, the
  // planet saved (throws, naming the file, if the disk refuses).
  void finish() {
    stepper_.endStroke();
    stopRecording();  // cmd_live prints the recordings
    if (const auto x = exporter_.wait()) reportExport(*x);
    if (shell_.interrupted) std::cerr << "live: interrupted; saving the planet\n";
    store_.save(now());
    const session::SessionWriterStats w = store_.writerStats();
    if (w.records > 0) {
      char line[256];
      std::snprintf(line, sizeof line,
                    "live: journal: %zu record%s written and flushed by the writer thread, %.1f "
                    "ms on average, %.1f ms at most, on disk %.1f ms after the stroke at most; "
                    "saves %.0f ms at most (the last %.0f ms); the frame's copy %.2f ms at most\n",
                    w.records, w.records == 1 ? "" : "s", w.recordTotalMs / double(w.records),
                    w.recordMaxMs, w.recordLagMaxMs, w.saveMaxMs, w.lastSaveMs, store_.copyMaxMs());
      std::cerr << line;
    }
    result_.saved = savePath_;
    result_.strokes = stepper_.summary().strokes;
  }

  void save() {
    stepper_.endStroke();
    store_.save(now());
  }

  // The sidecar is opened with the recording's first frame, so that its header holds the
  // planet and the settings that frame meets (a camera may be lost when recording starts).
  void startRecording(const std::filesystem::path& video) {
    recorder_.start(video, shell_.input.fps());
    sidecarPending_ = true;
  }
  void openSidecar() {
    sidecarPending_ = false;
    const std::filesystem::path video = recorder_.path();
    stepper_.endStroke();  // a replay begins with no stroke open
    // The start: the planet as given, or (recovered, or sculpted before this recording) a copy
    // of it beside the video, so that the replay starts from it.
    std::string planetFile = settings_.start.planetFile;
    if (recovered_ || io::heightsChecksum(planet_.heights()) != startCrc_) {
      planetFile = video.string() + ".start.planet";
      io::savePlanet(planet_, planetFile);
    }
    const auto origin =
        replay::SessionStart::of(planet_, planetFile, planet_.grid().side(), settings_.start.seed,
                                 calib_, settings_.start.calibrationFile, stepper_.options(),
                                 shell_.input.fps(), stepper_.pipeline().journal().undoCount());
    timeline_.open(replay::sessionSidecarPath(video), origin, settingsControl_.settings());
    settingsControl_.setWriter(&timeline_);
  }
  std::string stopRecording() {
    settingsControl_.setWriter(nullptr);
    timeline_.close();
    const std::filesystem::path p = recorder_.path();
    const int n = recorder_.stop();
    if (p.empty()) return std::string();
    result_.recordings.push_back(p);
    result_.recordedFrames.push_back(n);
    return "recorded " + std::to_string(n) + " frames to " + p.string();
  }

  void reportExport(const session::BackgroundExport::Outcome& x) {
    if (x.result) {
      char ms[32];
      std::snprintf(ms, sizeof ms, " in %.1f s", x.ms / 1000);
      note_ = x.result->describe() + ms;
      status_.exportPath = x.result->heightmap.string() + ", " + x.result->mesh.filename().string();
    } else {
      note_ = "not exported: " + x.error;
    }
    std::cerr << "live: " << note_ << "\n";
  }

  // The haptic force path beside the frame loop (docs/HAPTICS.md): a 1 kHz thread reads the
  // tracked tool tip (a position-only device) and the terrain near it; forces are computed,
  // drawn as an arrow and shown in the panel. Forces only: the tool's edits stay the
  // stepper's. The device's metres map to planet metres by the stepper's scale, so scaling the
  // planet by hand restarts the force path at the new scale (with a fresh device and clock).
  void startHaptics() {
    if (haptic_) haptic_->stopLoop();
    haptic_.reset();
    // Its press tool is the sand core's displacement: no forces on a chart the sand core does
    // not know (docs/CHARTS.md), said once.
    if (!sand::sandCoreKnows(planet_.chart())) {
      if (!hapticNoted_)
        std::cerr << "live: no haptic forces on the " << planet_.chart().name()
                  << " chart (the sand core does not work on it yet)\n";
      hapticNoted_ = true;
      return;
    }
    hapticConfig_.map.scale = stepper_.scale();
    hapticDevice_ = std::make_unique<haptics::TrackedMarkerDevice>();
    haptic_ = std::make_unique<haptics::ForcePath>(planet_, nullptr, hapticConfig_);
    haptic_->startLoop(*hapticDevice_);
  }

  Shell& shell_;
  const LiveSettings& settings_;
  LiveResult& result_;
  const tracking::CameraCalibration& calib_;
  const tracking::FrameUndistorter undistort_{calib_.forImageSize(shell_.camera)};
  const Eigen::Matrix3d K_;
  terrain::Terrain& planet_;
  const bool recovered_;
  const std::filesystem::path savePath_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  replay::FrameStepper stepper_;
  terrain::Tessellator tessellator_;
  terrain::SplicedView spliced_;  // the view with the sand TIN's region (viewPatch)
  Texture overview_;
  replay::HandOcclusion handOcclusion_;
  cv::Mat handMask_;  // this frame's, empty when nothing is in front of the planet
  Texture handView_;  // the AR view with the camera image over the hand
  bool showHandView_ = false;
  session::SessionStore store_;
  std::uint64_t savesSeen_ = 1;  // the store's save at the start
  replay::SettingsControl settingsControl_;
  replay::TimelineWriter timeline_;
  const std::uint32_t startCrc_;
  session::FrameRecorder recorder_;
  bool sidecarPending_ = false;
  const terrain::Camera placeholder_;
  const terrain::Mesh empty_;
  cv::Mat frame_;
  std::string note_;  // the last action's message (saved, undo refused, ...)
  PanelSettings panel_, applied_;
  PanelStatus status_;
  // Exports from the panel run in a thread of their own, on a copy of the planet; the
  // destructor waits for one still running when the session ends.
  session::BackgroundExport exporter_;
  std::optional<tracking::Pose> pose_;
  std::optional<core::GridPoint> controlVertex_;
  std::vector<Eigen::Vector3d> toolTriangles_;  // the tracked tool (planet frame), when posed
  double smoothedMs_ = 0;
  haptics::ForcePathConfig hapticConfig_;
  std::unique_ptr<haptics::TrackedMarkerDevice> hapticDevice_;
  std::unique_ptr<haptics::ForcePath> haptic_;
  bool hapticNoted_ = false;
  std::optional<haptics::ForceRecord> lastForce_;
};

}  // namespace

void runSculptLoop(Shell& shell, const tracking::CameraCalibration& calib, const Eigen::Matrix3d& K,
                   const replay::ReplayOptions& options, terrain::Terrain& planet, bool recovered,
                   const session::SessionFiles& files) {
  SculptLoop loop(shell, calib, K, options, planet, recovered, files);
  loop.run();
}

}  // namespace ps::live
