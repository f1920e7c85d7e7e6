#include "live/live_app.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "core/input_error.hpp"
#include "haptics/device.hpp"
#include "haptics/session.hpp"
#include "io/heightmap_export.hpp"
#include "io/planet_file.hpp"
#include "io/stroke_journal.hpp"
#include "live/panel.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "replay/session_timeline.hpp"
#include "session/frame_recorder.hpp"
#include "session/planet_export.hpp"
#include "session/session_store.hpp"
#include "terrain/tessellator.hpp"

namespace ps::live {

namespace {

std::atomic<bool> gInterrupted{false};
void onInterrupt(int) {
  gInterrupted = true;  // the loop saves and leaves; nothing else is safe in a handler
}

std::string gGlfwError;
void onGlfwError(int code, const char* what) {
  gGlfwError = "GLFW error " + std::to_string(code) + ": " + (what ? what : "");
}

// GLFW, initialised for the lifetime of the app.
struct GlfwLibrary {
  GlfwLibrary() {
    glfwSetErrorCallback(onGlfwError);
    if (!glfwInit())
      throw std::runtime_error("live: cannot start GLFW (no display? " + gGlfwError + ")");
  }
  ~GlfwLibrary() { glfwTerminate(); }
};

// Dear ImGui with its GLFW and OpenGL 3 back ends, for one window.
struct ImGuiLayer {
  explicit ImGuiLayer(GLFWwindow* window) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
  }
  ~ImGuiLayer() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
};

// The overview inset. It is drawn by the renderer every Nth frame only, so it cannot be a blit
// of the renderer's framebuffer (which holds the AR view the rest of the time): the image the
// renderer returns goes into a texture that ImGui draws every frame.
class Texture {
 public:
  Texture() { glGenTextures(1, &id_); }
  ~Texture() { glDeleteTextures(1, &id_); }
  Texture(const Texture&) = delete;
  Texture& operator=(const Texture&) = delete;
  void update(const cv::Mat& bgr) {
    cv::cvtColor(bgr, rgb_, cv::COLOR_BGR2RGB);
    glBindTexture(GL_TEXTURE_2D, id_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, rgb_.cols, rgb_.rows, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 rgb_.data);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glBindTexture(GL_TEXTURE_2D, 0);
    valid_ = true;
  }
  bool valid() const { return valid_; }
  ImTextureID imgui() const {
    return reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(id_));
  }

 private:
  GLuint id_ = 0;
  cv::Mat rgb_;
  bool valid_ = false;
};

Eigen::Matrix3d eigenK(const cv::Matx33d& K) {
  Eigen::Matrix3d k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
  return k;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The window's back buffer as BGR, top row first.
cv::Mat windowPixels(int width, int height) {
  cv::Mat rgba(height, width, CV_8UC4), bgr, flipped;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data);
  cv::cvtColor(rgba, bgr, cv::COLOR_RGBA2BGR);
  cv::flip(bgr, flipped, 0);
  return flipped;
}

std::string records(std::size_t n) {
  return std::to_string(n) + (n == 1 ? " record" : " records");
}

PanelSettings panelFrom(const LiveSettings& s) {
  PanelSettings p;
  const auto& o = s.options;
  p.displace = o.tool == replay::ReplayTool::kDisplace;
  p.brushRadiusKm = float(o.brush.radius / 1e3);
  p.strengthM = float(o.brush.strength);
  p.sigma = float(o.brush.sigma);
  p.lower = o.brush.mode == edit::BrushMode::kLower;
  p.displaceRadiusKm = float(o.displace.radius / 1e3);
  p.pressM = float(o.pressDepth);
  p.distMaxPx = float(s.distMaxPx);
  p.triangleBudget = int(s.triangleBudget);
  p.planetSizeCm = float(o.scene.planetRadius * 100);
  return p;
}

// Whether the panel's fields that change what the tool does (replay::SessionSettings) differ.
bool sculptingChanged(const PanelSettings& a, const PanelSettings& b) {
  return a.displace != b.displace || a.brushRadiusKm != b.brushRadiusKm ||
         a.strengthM != b.strengthM || a.sigma != b.sigma || a.lower != b.lower ||
         a.displaceRadiusKm != b.displaceRadiusKm || a.pressM != b.pressM ||
         a.spinDeg != b.spinDeg || a.tiltDeg != b.tiltDeg || a.planetSizeCm != b.planetSizeCm;
}

// The settings the panel asks for, from those in effect (fields the panel does not show, and
// the brush mode unless raise/lower was toggled, so a `--mode set` session stays in set mode).
replay::SessionSettings panelTarget(const PanelSettings& p, const PanelSettings& applied,
                                    const replay::SessionSettings& now) {
  replay::SessionSettings t = now;
  t.tool = p.displace ? replay::ReplayTool::kDisplace : replay::ReplayTool::kBrush;
  t.brush.radius = p.brushRadiusKm * 1e3;
  t.brush.strength = p.strengthM;
  t.brush.sigma = p.sigma;
  if (p.lower != applied.lower)
    t.brush.mode = p.lower ? edit::BrushMode::kLower : edit::BrushMode::kRaise;
  t.displace.radius = p.displaceRadiusKm * 1e3;
  t.pressDepth = p.pressM;
  t.spinDeg = p.spinDeg;
  t.tiltDeg = p.tiltDeg;
  t.planetRadius = double(p.planetSizeCm) / 100;
  return t;
}

}  // namespace

LiveResult runLive(FrameInput& input, const tracking::CameraCalibration& calibration,
                   std::unique_ptr<terrain::Terrain>& planetPtr, const LiveSettings& settings) {
  if (settings.overviewEvery < 1) throw core::InputError("overview every N frames: N must be >= 1");
  if (!planetPtr) throw core::InputError("live: no planet");
  const terrain::Terrain* const startPlanet = planetPtr.get();  // a recovered one replaces it
  replay::ReplayOptions options = settings.options;
  options.undo = true;
  options.validate();
  const tracking::CameraCalibration calib = calibration.forImageSize(input.size());
  std::filesystem::create_directories(settings.out);
  const session::SessionFiles files = session::SessionFiles::in(settings.out);
  const std::filesystem::path savePath = files.planet;

  // A journal left by a session that did not end (docs/LIVE.md): recover, discard, or ask.
  const session::Recovery recovery = session::Recovery::inspect(files);
  bool ask = false;
  auto recover = [&] {
    planetPtr = recovery.recover();
    std::cerr << "live: recovered " << records(recovery.records()) << " of "
              << files.journal.string() << " into the planet of " << files.planet.string() << "\n";
  };
  auto discard = [&] {
    const auto to = recovery.setAside();
    std::cerr << "live: discarded the journal's records (kept as " << to.string() << ")\n";
  };
  switch (recovery.state()) {
    case session::Recovery::State::kNone:
      if (!recovery.message().empty()) std::cerr << "live: " << recovery.message() << "\n";
      break;
    case session::Recovery::State::kAlreadySaved:
      std::cerr << "live: " << recovery.message() << "\n";
      break;
    case session::Recovery::State::kRefused: {
      std::cerr << "live: " << recovery.message() << "\n";
      const auto to = recovery.setAside();
      std::cerr << "live: kept it as " << to.string() << "\n";
      break;
    }
    case session::Recovery::State::kRecoverable:
      std::cerr << "live: " << recovery.message() << "\n";
      if (settings.journal == JournalChoice::kRecover)
        recover();
      else if (settings.journal == JournalChoice::kDiscard)
        discard();
      else
        ask = true;
      break;
  }

  GlfwLibrary glfw;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  const int W = input.size().width, H = input.size().height;
  GLFWwindow* window =
      glfwCreateWindow(std::max(W, 960), std::max(H, 720), "PlanetSculpt live", nullptr, nullptr);
  if (!window)
    throw std::runtime_error("live: cannot open a window with OpenGL 3.3 core (" + gGlfwError +
                             ")");
  struct WindowGuard {
    GLFWwindow* w;
    ~WindowGuard() { glfwDestroyWindow(w); }
  } windowGuard{window};
  glfwMakeContextCurrent(window);
  glfwSwapInterval(settings.frames > 0 ? 0 : 1);

  LiveResult result;
  {
    render::PlanetRenderer renderer;
    ImGuiLayer imgui(window);
    gInterrupted = false;
    const auto previousHandler = std::signal(SIGINT, onInterrupt);
    struct SignalGuard {
      void (*previous)(int);
      ~SignalGuard() { std::signal(SIGINT, previous); }
    } signalGuard{previousHandler};
    const Eigen::Matrix3d K = eigenK(calib.K);
    const terrain::Mesh empty;
    cv::Mat image = cv::Mat::zeros(H, W, CV_8UC3), frame;
    auto running = [&] {
      return !glfwWindowShouldClose(window) && !gInterrupted &&
             (settings.frames == 0 || result.frames < settings.frames);
    };
    // Draws the camera image (and the planet's mesh, when there is one) into the window.
    auto presentView = [&](const terrain::Terrain& planet, const terrain::Mesh& mesh,
                           const terrain::Camera& cam, const render::RenderStyle& style,
                           const std::optional<render::Cursor>& cursor, int& fbW, int& fbH) {
      renderer.renderAR(image, planet, mesh, cam, style, cursor);
      glfwGetFramebufferSize(window, &fbW, &fbH);
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      glViewport(0, 0, fbW, fbH);
      glClearColor(0.02f, 0.02f, 0.03f, 1);
      glClear(GL_COLOR_BUFFER_BIT);
      // Fit the camera's aspect into the window, centred.
      const double fit = std::min(double(fbW) / W, double(fbH) / H);
      const int vw = int(W * fit), vh = int(H * fit);
      renderer.present((fbW - vw) / 2, (fbH - vh) / 2, vw, vh);
    };
    auto finishFrame = [&](int fbW, int fbH) {
      ImGui::Render();
      glBindFramebuffer(GL_FRAMEBUFFER, 0);  // the window, whatever the renderer left bound
      glViewport(0, 0, fbW, fbH);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      if (!settings.screenshot.empty() && settings.frames > 0 &&
          result.frames + 1 == settings.frames)
        io::writePngAtomically(windowPixels(fbW, fbH), settings.screenshot);
      glfwSwapBuffers(window);
    };

    // The recovery question: the camera image and a modal; nothing is sculpted, saved or
    // journaled until it is answered.
    std::string recoveryNote;
    if (ask) {
      std::cerr << "live: choose Recover or Discard in the window (or run again with --recover "
                   "or --discard-journal)"
                << std::endl;
      const terrain::Camera placeholder =
          render::arCamera(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1), 1.0, K, W, H);
      while (ask && running()) {
        glfwPollEvents();
        // A camera's picture goes on; a video waits for the answer (its frames are the session's).
        if (input.isCamera() && input.read(frame)) image = frame;
        int fbW = 0, fbH = 0;
        presentView(*planetPtr, empty, placeholder, {}, std::nullopt, fbW, fbH);
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        const RecoveryAnswer answer = drawRecoveryModal(recovery.message() + recoveryNote);
        // Esc closes the window unanswered, like the window's close button.
        if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false))
          glfwSetWindowShouldClose(window, GLFW_TRUE);
        finishFrame(fbW, fbH);
        ++result.frames;
        try {
          if (answer == RecoveryAnswer::kRecover) recover();
          if (answer == RecoveryAnswer::kDiscard) discard();
          if (answer != RecoveryAnswer::kNone) ask = false;
        } catch (const std::exception& e) {
          recoveryNote = std::string("\n\nnot recovered: ") + e.what();
          std::cerr << "live: not recovered: " << e.what() << "\n";
        }
      }
      if (ask) {
        result.journalKept = true;
        std::cerr << "live: the window closed before the recovery question was answered: "
                  << files.journal.string() << " (" << records(recovery.records()) << ") and "
                  << files.planet.string()
                  << " are left as they were; run again with --recover or --discard-journal\n";
        return result;
      }
    }

    terrain::Terrain& planet = *planetPtr;
    replay::FrameStepper stepper(calib, planet, options);
    terrain::Tessellator tessellator;
    Texture overview;
    // The planet on disk: saved now, then autosaved; every stroke, undo and redo journaled.
    const auto start = std::chrono::steady_clock::now();
    auto now = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    session::SessionStore store(planet, files, {settings.autosaveSeconds, true}, now());
    stepper.pipeline().journal().setListener(&store);
    struct ListenerGuard {
      edit::UndoJournal& journal;
      ~ListenerGuard() { journal.setListener(nullptr); }
    } listenerGuard{stepper.pipeline().journal()};
    // Every settings change, undo and redo goes through `sessionControl`, which also writes it
    // to the recording's sidecar (replay/session_timeline.hpp): a replay applies them the same
    // way.
    replay::SessionControl sessionControl(stepper);
    replay::TimelineWriter timeline;
    const std::uint32_t startCrc = io::heightsChecksum(planet.heights());
    const bool recovered = planetPtr.get() != startPlanet;
    std::string note;  // last action's message (saved, undo refused, ...)
    session::FrameRecorder recorder;
    auto stopRecording = [&] {
      sessionControl.setWriter(nullptr);
      timeline.close();
      const std::filesystem::path p = recorder.path();
      const int n = recorder.stop();
      if (p.empty()) return std::string();
      result.recordings.push_back(p);
      result.recordedFrames.push_back(n);
      return "recorded " + std::to_string(n) + " frames to " + p.string();
    };
    // The sidecar is opened with the recording's first frame, so that its header holds the
    // planet and the settings that frame meets (a camera may be lost when recording starts).
    bool sidecarPending = false;
    auto startRecording = [&](const std::filesystem::path& video) {
      recorder.start(video, input.fps());
      sidecarPending = true;
    };
    auto openSidecar = [&] {
      sidecarPending = false;
      const std::filesystem::path video = recorder.path();
      stepper.endStroke();  // a replay begins with no stroke open
      // The start: the planet as given, or (recovered, or sculpted before this recording) a
      // copy of it beside the video, so that the replay starts from it.
      std::string planetFile = settings.start.planetFile;
      if (recovered || io::heightsChecksum(planet.heights()) != startCrc) {
        planetFile = video.string() + ".start.planet";
        io::savePlanet(planet, planetFile);
      }
      const auto origin =
          replay::SessionStart::of(planet, planetFile, planet.grid().side(), settings.start.seed,
                                   calib, settings.start.calibrationFile, stepper.options(),
                                   input.fps(), stepper.pipeline().journal().undoCount());
      timeline.open(replay::sessionSidecarPath(video), origin, sessionControl.settings());
      sessionControl.setWriter(&timeline);
    };
    if (!settings.record.empty()) startRecording(settings.record);

    // With no planet pose yet: the camera image alone (an empty mesh, any valid camera).
    const terrain::Camera placeholder = render::arCamera(
        Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1), stepper.scale(), K, W, H);
    PanelSettings panel = panelFrom(settings), applied = panel;
    PanelStatus status;
    status.savePath = savePath.string();
    // Exports from the panel run in a thread of their own, on a copy of the planet; the
    // destructor waits for one still running when the session ends.
    session::BackgroundExport exporter;
    auto reportExport = [&](const session::BackgroundExport::Outcome& x) {
      if (x.result) {
        char ms[32];
        std::snprintf(ms, sizeof ms, " in %.1f s", x.ms / 1000);
        note = x.result->describe() + ms;
        status.exportPath =
            x.result->heightmap.string() + ", " + x.result->mesh.filename().string();
      } else {
        note = "not exported: " + x.error;
      }
      std::cerr << "live: " << note << "\n";
    };
    std::optional<tracking::Pose> pose;
    std::optional<core::GridPoint> control;
    double smoothedMs = 0;
    auto save = [&] {
      stepper.endStroke();
      store.save(now());
    };

    // Whatever goes wrong inside the loop, the planet is saved before the error goes on.
    struct SaveOnError {
      const std::function<void()> save;
      ~SaveOnError() {
        if (std::uncaught_exceptions() > 0) try {
            save();
            std::cerr << "live: the planet was saved before the error\n";
          } catch (...) {
          }
      }
    } saveOnError{[&] {
      recorder.stop();
      save();
    }};
    // The haptic force path beside the frame loop (docs/HAPTICS.md): a 1 kHz thread reads the
    // tracked tool tip (a position-only device) and the terrain near it; forces are computed,
    // drawn as an arrow and shown in the panel. Forces only: the tool's edits stay the
    // stepper's.
    // The device's metres map to planet metres by the stepper's scale, so scaling the planet
    // by hand restarts the force path at the new scale (with a fresh device and clock).
    haptics::SessionConfig hapticConfig;
    std::unique_ptr<haptics::TrackedMarkerDevice> hapticDevice;
    std::unique_ptr<haptics::HapticSession> haptic;
    auto startHaptics = [&] {
      if (haptic) haptic->stopLoop();
      haptic.reset();
      hapticConfig.map.scale = stepper.scale();
      hapticDevice = std::make_unique<haptics::TrackedMarkerDevice>();
      haptic = std::make_unique<haptics::HapticSession>(planet, nullptr, hapticConfig);
      haptic->startLoop(*hapticDevice);
    };
    startHaptics();
    struct LoopGuard {
      std::unique_ptr<haptics::HapticSession>& h;
      ~LoopGuard() {
        if (h) h->stopLoop();
      }
    } loopGuard{haptic};
    std::optional<haptics::ForceRecord> lastForce;
    std::cerr << "live: window open (" << reinterpret_cast<const char*>(glGetString(GL_RENDERER))
              << "); close it, press Esc or Ctrl-C to save and quit" << std::endl;
    while (running()) {
      const auto t0 = std::chrono::steady_clock::now();
      glfwPollEvents();
      status.trackMs = status.editMs = 0;
      if (input.read(frame)) {
        image = frame;
        if (recorder.recording()) try {
            if (sidecarPending) openSidecar();  // no recording without its sidecar
            recorder.write(frame);
            timeline.frameRecorded(input.time());
          } catch (const std::exception& e) {
            note = std::string("recording stopped: ") + e.what();
            stopRecording();
          }
        const auto r = stepper.step(frame, input.index(), input.time());
        if (!r.settled.empty()) store.recordRegion(r.settled);
        status.trackMs = r.times.detectMs + r.times.trackMs;
        status.editMs = r.times.editMs;
        pose = r.planetInCamera;
        control = r.control;
        status.touching = r.touching;
        const double t = haptic->loop()->now();
        if (r.scene.tipValid)
          hapticDevice->push(r.scene.tipPlanet, t);
        else
          hapticDevice->push(Eigen::Vector3d::Constant(std::nan("")), t);
        status.planetState = tracking::toString(r.scene.planet.state);
        status.toolState = tracking::toString(r.scene.tool.state);
      } else {
        // No frame (camera lost, video ended): the tool is not seen, so no stroke goes on; the
        // last image and the planet on it stay.
        stepper.endStroke();
        status.touching = false;
        control.reset();
      }
      {
        const auto forces = haptic->editorFrame();
        if (forces.last) lastForce = forces.last;
        status.forceN = lastForce && lastForce->touching ? lastForce->force.norm() : 0.0;
        const double elapsed = haptic->loop()->now();
        status.hapticHz = elapsed > 0 ? double(haptic->loop()->stats().ticks) / elapsed : 0.0;
      }
      if (const auto x = exporter.poll()) reportExport(*x);
      // Autosave between strokes.
      if (store.tick(now(), stepper.pipeline().inStroke())) {
        ++result.autosaves;
        char ms[32];
        std::snprintf(ms, sizeof ms, " (%.0f ms)", store.lastSaveMs());
        note = "autosaved " + savePath.string() + ms;
        std::cerr << "live: " << note << "\n";
      }
      if (!store.error().empty()) note = store.error();
      if (!timeline.error().empty()) note = timeline.error();
      status.autosaveInS =
          settings.autosaveSeconds > 0
              ? std::max(0.0, store.lastSaveTime() + settings.autosaveSeconds - now())
              : -1.0;
      status.journalRecords = store.recordsSinceSave();
      status.recordPath = recorder.recording() ? recorder.path().string() : "";
      status.recordedFrames = recorder.frames();
      status.message = input.status();
      if (!note.empty()) status.message += (status.message.empty() ? "" : "\n") + note;

      // The AR view, through the renderer's framebuffer, blitted into the window.
      auto t1 = std::chrono::steady_clock::now();
      terrain::TessellationSettings ts;
      ts.distMaxPx = panel.distMaxPx;
      ts.triangleBudget = std::size_t(std::max(1000, panel.triangleBudget));
      render::RenderStyle style;
      style.wireframe = panel.wireframe;
      style.contours = panel.contours;
      std::optional<terrain::Camera> cam;
      const terrain::Mesh* mesh = &empty;
      if (pose) {
        cam = render::arCamera(pose->R, pose->t, stepper.scale(), K, W, H);
        mesh = &tessellator.tessellate(planet, *cam, ts);
        status.reused = tessellator.stats().reused;
        status.triangles = mesh->triangleCount();
      } else {
        status.triangles = 0;
        status.reused = false;
      }
      status.tessellateMs = msSince(t1);
      t1 = std::chrono::steady_clock::now();
      // The overview first: it uses the renderer's framebuffer too, and the AR view must be
      // the last image there when it is presented (and framebuffer 0 bound for the panel).
      if (cam && panel.showOverview && result.frames % settings.overviewEvery == 0)
        overview.update(renderer.renderOverview(planet, *mesh, *cam, 256, 256));
      std::optional<render::Cursor> cursor;
      if (control) {
        cursor = render::Cursor{*control, stepper.toolRadius()};
        // 8 N (the force clamp) draws as a quarter of the planet's radius.
        if (lastForce && lastForce->touching && lastForce->tipPlanet.allFinite()) {
          cursor->arrowFrom = lastForce->tipPlanet;
          cursor->arrow = lastForce->force * (0.25 * planet.chart().radius() / 8.0);
        }
      }
      int fbW = 0, fbH = 0;
      presentView(planet, *mesh, cam ? *cam : placeholder, style, cursor, fbW, fbH);
      status.renderMs = msSince(t1);

      // The panel.
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      PanelActions actions;
      applyShortcuts(panel, actions);
      status.undoCount = stepper.pipeline().journal().undoCount();
      status.redoCount = stepper.pipeline().journal().redoCount();
      drawPanel(panel, actions, status);
      applyScript(settings.script, result.frames, actions, panel);
      if (actions.crash) std::raise(SIGKILL);  // a scripted crash: nothing saved, nothing flushed
      if (actions.interrupt) std::raise(SIGINT);  // handled as a Ctrl-C from outside is
      if (panel.showOverview && overview.valid()) {
        const ImVec2 display = ImGui::GetIO().DisplaySize;
        ImGui::SetNextWindowPos(ImVec2(display.x - 8, display.y - 8), ImGuiCond_Always,
                                ImVec2(1, 1));
        ImGui::SetNextWindowBgAlpha(0.6f);
        ImGui::Begin("overview", nullptr,
                     ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoDecoration);
        ImGui::Image(overview.imgui(), ImVec2(256, 256));
        ImGui::End();
      }
      if (!input.status().empty()) {
        ImDrawList* draw = ImGui::GetForegroundDrawList();
        const ImVec2 display = ImGui::GetIO().DisplaySize;
        draw->AddText(nullptr, 22, ImVec2(16, display.y * 0.5f), IM_COL32(255, 90, 60, 255),
                      input.status().c_str());
      }
      finishFrame(fbW, fbH);

      // What the user asked for.
      if (sculptingChanged(panel, applied)) {
        const double scale = stepper.scale();
        try {
          sessionControl.apply(panelTarget(panel, applied, sessionControl.settings()));
          applied = panel;
        } catch (const core::InputError& e) {
          note = e.what();  // the refused value is kept out; the rest applies
        }
        if (stepper.scale() != scale) startHaptics();
      }
      try {
        if (actions.undo) {
          sessionControl.undo();
          note = "undone";
        }
        if (actions.redo) {
          sessionControl.redo();
          note = "redone";
        }
      } catch (const core::InputError& e) {
        note = e.what();
      }
      if (actions.save) {
        try {
          save();
          note = "saved " + savePath.string();
        } catch (const std::exception& e) {
          note = std::string("not saved: ") + e.what();
        }
      }
      if (actions.exportPlanet) {
        try {
          exporter.start(planet, settings.out / "exports");  // a copy, written by a thread
          note = "exporting to " + (settings.out / "exports").string() + " ...";
          status.exportPath = "exporting ...";
        } catch (const std::exception& e) {
          note = std::string("not exported: ") + e.what();
        }
      }
      if (actions.record) {
        try {
          if (recorder.recording()) {
            note = stopRecording();
          } else {
            startRecording(session::nextRecordingPath(settings.out));
            note = "recording to " + recorder.path().string();
          }
        } catch (const std::exception& e) {
          note = std::string("recording: ") + e.what();
        }
      }
      if (actions.quit) glfwSetWindowShouldClose(window, GLFW_TRUE);
      const double ms = msSince(t0);
      smoothedMs = smoothedMs == 0 ? ms : 0.9 * smoothedMs + 0.1 * ms;
      status.frameMs = smoothedMs;
      status.fps = smoothedMs > 0 ? 1000 / smoothedMs : 0;
      ++result.frames;
    }
    stepper.endStroke();
    stopRecording();  // cmd_live prints the recordings
    if (const auto x = exporter.wait()) reportExport(*x);
    if (gInterrupted) std::cerr << "live: interrupted; saving the planet\n";
    store.save(now());  // throws (naming the file) if the disk refuses
    if (store.recordsWritten() > 0) {
      char line[160];
      std::snprintf(line, sizeof line,
                    "live: journal: %zu record%s written and flushed, %.1f ms on average, %.1f "
                    "ms at most; last save %.0f ms\n",
                    store.recordsWritten(), store.recordsWritten() == 1 ? "" : "s",
                    store.recordTotalMs() / double(store.recordsWritten()), store.recordMaxMs(),
                    store.lastSaveMs());
      std::cerr << line;
    }
    result.saved = savePath;
    result.strokes = stepper.summary().strokes;
  }
  return result;
}

}  // namespace ps::live
