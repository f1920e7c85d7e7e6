#pragma once
// Frames from an image file, an image folder or a video file, and lossless video writing
// (FFV1 in Matroska: bit-exact on read-back). Every failure names the file and, where it
// matters, the frame.
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

namespace ps::tracking {

bool isImageFile(const std::filesystem::path& path);

class FrameSource {
 public:
  // A single image, a folder of images (sorted by name) or a video. Throws core::InputError
  // "PATH: ..." when the path is missing, unreadable, not an image or video OpenCV can decode,
  // or holds no frame at all.
  explicit FrameSource(const std::filesystem::path& path);

  // Next frame (BGR or grey as decoded) into `frame`; false at the end. A video that ends before
  // the frame count its container announced sets truncated().
  bool read(cv::Mat& frame);

  const std::string& name() const { return name_; }
  int index() const { return index_; }  // the frame last read (0-based; -1 before the first)
  cv::Size size() const { return size_; }
  double fps() const { return fps_; }  // 0 for images (taken as 30 by callers that need one)
  int announcedFrames() const { return announced_; }  // the container's count, -1 unknown
  bool isVideo() const { return capture_ != nullptr; }
  bool truncated() const { return truncated_; }
  // Path of the current frame (image folders), else the source's name.
  std::string frameName() const;

 private:
  std::string name_;
  std::unique_ptr<cv::VideoCapture> capture_;
  std::vector<std::filesystem::path> images_;
  cv::Mat first_;
  bool firstPending_ = false;
  int index_ = -1;
  cv::Size size_;
  double fps_ = 0;
  int announced_ = -1;
  bool truncated_ = false;
};

// FFV1 in .mkv (lossless). Throws std::runtime_error when OpenCV's FFmpeg back end cannot open
// the file for writing; frames must all have the writer's size and channel count.
class LosslessWriter {
 public:
  LosslessWriter(const std::filesystem::path& path, cv::Size size, double fps, bool colour);
  void write(const cv::Mat& frame);
  void close();
  int frames() const { return frames_; }

 private:
  std::string name_;
  cv::VideoWriter writer_;
  cv::Size size_;
  bool colour_;
  int frames_ = 0;
};

}  // namespace ps::tracking
