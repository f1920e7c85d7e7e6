#pragma once
// `planetsculpt live --record FILE` and the panel's record toggle: the camera frames the app
// processes, written losslessly (FFV1 in Matroska, grey or BGR as they come, like data/demo.mkv)
// so that `planetsculpt replay FILE` replays the session.
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>

#include "tracking/video.hpp"

namespace ps::session {

class FrameRecorder {
 public:
  // The video is created at the first frame (its size and channels fix the video's).
  void start(const std::filesystem::path& path, double fps);
  // Writes `frame` when recording. Throws std::runtime_error or std::invalid_argument naming the
  // file when the writer refuses (the recording is then stopped).
  void write(const cv::Mat& frame);
  // Closes the video; returns its frame count (0 when not recording).
  int stop();

  bool recording() const { return path_.has_value(); }
  const std::filesystem::path& path() const;
  int frames() const { return writer_ ? writer_->frames() : 0; }

 private:
  std::optional<std::filesystem::path> path_;
  double fps_ = 30;
  std::unique_ptr<tracking::LosslessWriter> writer_;
};

// The first OUT/recording-NNN.mkv (NNN = 001, 002, ...) that does not exist yet.
std::filesystem::path nextRecordingPath(const std::filesystem::path& outDir);

}  // namespace ps::session
