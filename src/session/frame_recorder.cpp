#include "session/frame_recorder.hpp"

#include <cstdio>
#include <stdexcept>

#include "core/input_error.hpp"

namespace ps::session {

void FrameRecorder::start(const std::filesystem::path& path, double fps) {
  stop();
  if (!(fps > 0)) fps = 30;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  path_ = path;
  fps_ = fps;
}

void FrameRecorder::write(const cv::Mat& frame) {
  if (!path_) return;
  try {
    if (!writer_) {
      if (frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3))
        throw std::invalid_argument(path_->string() + ": frames must be 8-bit grey or BGR");
      writer_ = std::make_unique<tracking::LosslessWriter>(*path_, frame.size(), fps_,
                                                           frame.channels() == 3);
    }
    writer_->write(frame);
  } catch (...) {
    stop();
    throw;
  }
}

int FrameRecorder::stop() {
  const int n = frames();
  if (writer_) writer_->close();
  writer_.reset();
  path_.reset();
  return n;
}

const std::filesystem::path& FrameRecorder::path() const {
  static const std::filesystem::path none;
  return path_ ? *path_ : none;
}

std::filesystem::path nextRecordingPath(const std::filesystem::path& outDir) {
  for (int i = 1; i < 100000; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "recording-%03d.mkv", i);
    if (!std::filesystem::exists(outDir / name)) return outDir / name;
  }
  throw core::InputError(outDir.string() + ": no free recording-NNN.mkv name");
}

}  // namespace ps::session
