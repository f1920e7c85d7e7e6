#pragma once
// Frames for the live app: a camera (OpenCV capture by index) or a video file
// (tracking::FrameSource). A camera that stops delivering is "lost": read() returns false and
// status() says so; it is reopened every couple of seconds, and frames resume when it answers.
// A video that ends stays ended (its last frame is the last one).
#include <chrono>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>

#include "tracking/video.hpp"

namespace ps::live {

class FrameInput {
 public:
  // Throws core::InputError naming the camera or file when nothing can be opened or the first
  // frame does not come.
  static FrameInput camera(int index);
  static FrameInput video(const std::filesystem::path& path);

  // The next frame; false when there is none now (camera lost, video ended).
  bool read(cv::Mat& frame);
  cv::Size size() const { return size_; }
  // Seconds of the frame last read: the video's frame time, or the wall clock for a camera.
  double time() const { return time_; }
  // Frames per second: the video's, or 30 for a camera (nominal: cameras vary).
  double fps() const { return fps_; }
  int index() const { return index_; }
  bool isCamera() const { return cameraIndex_ >= 0; }
  bool ended() const { return ended_; }  // video: no more frames
  bool lost() const { return lost_; }    // camera: no frame at the last read
  // "" while frames come; else what happened, for the screen.
  std::string status() const;
  std::string name() const;

 private:
  FrameInput() = default;
  int cameraIndex_ = -1;
  std::unique_ptr<cv::VideoCapture> capture_;
  std::unique_ptr<tracking::FrameSource> source_;
  cv::Mat first_;
  bool firstPending_ = false;
  cv::Size size_;
  double fps_ = 30;
  double time_ = 0;
  int index_ = -1;
  bool ended_ = false, lost_ = false;
  std::chrono::steady_clock::time_point start_, lastReopen_;
};

}  // namespace ps::live
