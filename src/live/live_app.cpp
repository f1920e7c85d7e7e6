#include "live/live_app.hpp"

#define GLFW_INCLUDE_NONE  // events and key codes only; the window is live/gl_window's
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <csignal>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "core/input_error.hpp"
#include "live/gl_window.hpp"
#include "live/live_shell.hpp"
#include "live/panel.hpp"
#include "live/sculpt_loop.hpp"
#include "live/window_layout.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "session/session_store.hpp"

namespace ps::live {

namespace {

std::atomic<bool> gInterrupted{false};
void onInterrupt(int) {
  gInterrupted = true;  // the loop saves and leaves; nothing else is safe in a handler
}

// Ctrl-C saves and leaves, for as long as the window is open.
class InterruptHandler {
 public:
  InterruptHandler() {
    gInterrupted = false;
    previous_ = std::signal(SIGINT, onInterrupt);
  }
  ~InterruptHandler() { std::signal(SIGINT, previous_); }
  InterruptHandler(const InterruptHandler&) = delete;
  InterruptHandler& operator=(const InterruptHandler&) = delete;

 private:
  void (*previous_)(int) = nullptr;
};

Eigen::Matrix3d eigenK(const cv::Matx33d& K) {
  Eigen::Matrix3d k;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) k(i, j) = K(i, j);
  return k;
}

std::string records(std::size_t n) {
  return std::to_string(n) + (n == 1 ? " record" : " records");
}

// A journal left by a session that did not end (docs/LIVE.md): recovered into the planet, set
// aside, or left for the window to ask about.
class JournalAtStart {
 public:
  JournalAtStart(const session::SessionFiles& files, std::unique_ptr<terrain::Terrain>& planet)
      : files_(files), planet_(planet), recovery_(session::Recovery::inspect(files)) {}

  // Does what the command line chose; true when the window must ask.
  bool settle(JournalChoice choice) const {
    switch (recovery_.state()) {
      case session::Recovery::State::kNone:
        if (!recovery_.message().empty()) std::cerr << "live: " << recovery_.message() << "\n";
        return false;
      case session::Recovery::State::kAlreadySaved:
        std::cerr << "live: " << recovery_.message() << "\n";
        return false;
      case session::Recovery::State::kRefused: {
        std::cerr << "live: " << recovery_.message() << "\n";
        const auto to = recovery_.setAside();
        std::cerr << "live: kept it as " << to.string() << "\n";
        return false;
      }
      case session::Recovery::State::kRecoverable:
        std::cerr << "live: " << recovery_.message() << "\n";
        if (choice == JournalChoice::kRecover)
          recover();
        else if (choice == JournalChoice::kDiscard)
          discard();
        return choice == JournalChoice::kAsk;
    }
    return false;
  }
  void recover() const {
    planet_ = recovery_.recover();
    std::cerr << "live: recovered " << records(recovery_.records()) << " of "
              << files_.journal.string() << " into the planet of " << files_.planet.string()
              << "\n";
  }
  void discard() const {
    const auto to = recovery_.setAside();
    std::cerr << "live: discarded the journal's records (kept as " << to.string() << ")\n";
  }
  const session::Recovery& recovery() const { return recovery_; }
  const terrain::Terrain& planet() const { return *planet_; }

 private:
  const session::SessionFiles& files_;
  std::unique_ptr<terrain::Terrain>& planet_;
  const session::Recovery recovery_;
};

// The recovery question: the camera image and a modal; nothing is sculpted, saved or journaled
// until it is answered. False when the window closed first.
bool askRecovery(Shell& shell, const JournalAtStart& journal, const Eigen::Matrix3d& K) {
  std::cerr << "live: choose Recover or Discard in the window (or run again with --recover "
               "or --discard-journal)"
            << std::endl;
  const terrain::Camera placeholder =
      render::arCamera(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1), 1.0, K,
                       shell.camera.width, shell.camera.height);
  const terrain::Mesh empty;
  std::string note;
  cv::Mat frame;
  while (shell.running()) {
    glfwPollEvents();
    // A camera's picture goes on; a video waits for the answer (its frames are the session's).
    if (shell.input.isCamera() && shell.input.read(frame)) shell.image = frame;
    const cv::Size fb = shell.present(journal.planet(), empty, placeholder, {}, std::nullopt);
    shell.imgui.newFrame();
    const RecoveryAnswer answer = drawRecoveryModal(journal.recovery().message() + note);
    // Esc closes the window unanswered, like the window's close button.
    if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) shell.window.requestClose();
    shell.finish(fb);
    ++shell.result.frames;
    try {
      if (answer == RecoveryAnswer::kRecover) journal.recover();
      if (answer == RecoveryAnswer::kDiscard) journal.discard();
      if (answer != RecoveryAnswer::kNone) return true;
    } catch (const std::exception& e) {
      note = std::string("\n\nnot recovered: ") + e.what();
      std::cerr << "live: not recovered: " << e.what() << "\n";
    }
  }
  return false;
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
  const JournalAtStart journal(files, planetPtr);
  const bool ask = journal.settle(settings.journal);

  GlfwLibrary glfw;
  const int W = input.size().width, H = input.size().height;
  const cv::Size windowSize = windowSizeFor({W, H});
  Window window(windowSize.width, windowSize.height, "PlanetSculpt live", settings.frames == 0);
  LiveResult result;
  render::PlanetRenderer renderer;
  ImGuiLayer imgui(window);
  InterruptHandler interruptHandler;
  Shell shell{window, imgui, renderer, input, settings, result, gInterrupted};
  const Eigen::Matrix3d K = eigenK(calib.K);
  if (ask && !askRecovery(shell, journal, K)) {
    result.journalKept = true;
    std::cerr << "live: the window closed before the recovery question was answered: "
              << files.journal.string() << " (" << records(journal.recovery().records()) << ") and "
              << files.planet.string()
              << " are left as they were; run again with --recover or --discard-journal\n";
    return result;
  }
  runSculptLoop(shell, calib, K, options, *planetPtr, planetPtr.get() != startPlanet, files);
  return result;
}

}  // namespace ps::live
