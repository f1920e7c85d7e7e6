#include "live/frame_input.hpp"

#include "core/input_error.hpp"

namespace ps::live {

namespace {
double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

FrameInput FrameInput::camera(int index) {
  FrameInput in;
  in.cameraIndex_ = index;
  in.capture_ = std::make_unique<cv::VideoCapture>(index);
  if (!in.capture_->isOpened())
    throw core::InputError("camera " + std::to_string(index) +
                           ": cannot open it (is it connected?)");
  // The first frame fixes the size the calibration is scaled to; cameras take a moment to start.
  for (int attempt = 0; attempt < 50 && in.first_.empty(); ++attempt) in.capture_->read(in.first_);
  if (in.first_.empty())
    throw core::InputError("camera " + std::to_string(index) + ": opened, but no frame came");
  in.size_ = in.first_.size();
  in.firstPending_ = true;
  in.start_ = in.lastReopen_ = std::chrono::steady_clock::now();
  return in;
}

FrameInput FrameInput::video(const std::filesystem::path& path) {
  FrameInput in;
  in.source_ = std::make_unique<tracking::FrameSource>(path);
  in.size_ = in.source_->size();
  if (in.source_->fps() > 0) in.fps_ = in.source_->fps();
  in.start_ = in.lastReopen_ = std::chrono::steady_clock::now();
  return in;
}

bool FrameInput::read(cv::Mat& frame) {
  if (source_) {
    if (ended_ || !source_->read(frame)) {
      ended_ = true;
      return false;
    }
    index_ = source_->index();
    time_ = index_ / fps_;
    return true;
  }
  if (firstPending_) {
    frame = first_;
    firstPending_ = false;
  } else if (!capture_->read(frame) || frame.empty()) {
    lost_ = true;
    // Try to reopen the device every 2 s (unplugged and plugged back in).
    if (secondsSince(lastReopen_) > 2.0) {
      lastReopen_ = std::chrono::steady_clock::now();
      capture_ = std::make_unique<cv::VideoCapture>(cameraIndex_);
    }
    return false;
  }
  if (frame.size() != size_) {  // a reopened camera in another mode: not usable as calibrated
    lost_ = true;
    return false;
  }
  lost_ = false;
  ++index_;
  time_ = secondsSince(start_);
  return true;
}

std::string FrameInput::name() const {
  return source_ ? source_->name() : "camera " + std::to_string(cameraIndex_);
}

std::string FrameInput::status() const {
  if (ended_) return name() + ": the video ended; the planet is kept (close the window to save)";
  if (lost_) return name() + ": lost (no frame); the planet is kept, retrying every 2 s";
  return "";
}

}  // namespace ps::live
