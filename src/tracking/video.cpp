#include "tracking/video.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "core/input_error.hpp"

namespace ps::tracking {

bool isImageFile(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  static const char* kImage[] = {".png", ".jpg", ".jpeg", ".bmp",  ".tif", ".tiff",
                                 ".pgm", ".ppm", ".pbm",  ".webp", ".jp2"};
  return std::any_of(std::begin(kImage), std::end(kImage), [&](const char* e) { return ext == e; });
}

FrameSource::FrameSource(const std::filesystem::path& path) : name_(path.string()) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw core::InputError(name_ + ": no such file or folder");
  if (std::filesystem::is_directory(path, ec)) {
    for (const auto& e : std::filesystem::directory_iterator(path))
      if (e.is_regular_file() && isImageFile(e.path())) images_.push_back(e.path());
    std::sort(images_.begin(), images_.end());
    if (images_.empty()) throw core::InputError(name_ + ": the folder holds no image files");
    first_ = cv::imread(images_[0].string(), cv::IMREAD_UNCHANGED);
    if (first_.empty()) throw core::InputError(images_[0].string() + ": cannot decode the image");
    size_ = first_.size();
    announced_ = int(images_.size());
    firstPending_ = true;
    return;
  }
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw core::InputError(name_ + ": cannot open the file");
    if (probe.peek() == std::ifstream::traits_type::eof())
      throw core::InputError(name_ + ": the file is empty");
  }
  if (isImageFile(path)) {
    images_.push_back(path);
    first_ = cv::imread(name_, cv::IMREAD_UNCHANGED);
    if (first_.empty()) throw core::InputError(name_ + ": cannot decode the image");
    size_ = first_.size();
    announced_ = 1;
    firstPending_ = true;
    return;
  }
  capture_ = std::make_unique<cv::VideoCapture>();
  bool opened = false;
  try {
    opened = capture_->open(name_, cv::CAP_FFMPEG);
  } catch (const cv::Exception&) {
    opened = false;
  }
  if (!opened) throw core::InputError(name_ + ": not a video (or image) OpenCV can decode");
  fps_ = capture_->get(cv::CAP_PROP_FPS);
  if (!(fps_ > 0 && fps_ < 1000)) fps_ = 0;
  const double n = capture_->get(cv::CAP_PROP_FRAME_COUNT);
  announced_ = n > 0 && n < 1e9 ? int(n) : -1;
  if (!capture_->read(first_) || first_.empty())
    throw core::InputError(name_ + ": the video holds no decodable frame (empty or corrupt)");
  size_ = first_.size();
  firstPending_ = true;
}

bool FrameSource::read(cv::Mat& frame) {
  if (firstPending_) {
    firstPending_ = false;
    frame = first_;
    first_.release();
    index_ = 0;
    return true;
  }
  if (capture_) {
    cv::Mat f;
    bool ok = false;
    try {
      ok = capture_->read(f) && !f.empty();
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok) {
      if (announced_ > 0 && index_ + 1 < announced_) truncated_ = true;
      return false;
    }
    if (f.size() != size_) {
      truncated_ = true;  // a frame of another size: treated as the end of usable video
      return false;
    }
    frame = f;
    ++index_;
    return true;
  }
  if (index_ + 1 >= int(images_.size())) return false;
  ++index_;
  const auto& p = images_[std::size_t(index_)];
  frame = cv::imread(p.string(), cv::IMREAD_UNCHANGED);
  if (frame.empty()) throw core::InputError(p.string() + ": cannot decode the image");
  return true;
}

std::string FrameSource::frameName() const {
  if (!capture_ && index_ >= 0 && index_ < int(images_.size()))
    return images_[std::size_t(index_)].string();
  return name_;
}

LosslessWriter::LosslessWriter(const std::filesystem::path& path, cv::Size size, double fps,
                               bool colour)
    : name_(path.string()), size_(size), colour_(colour) {
  if (!writer_.open(name_, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), fps, size,
                    colour))
    throw std::runtime_error(name_ + ": cannot open for writing an FFV1 video");
}

void LosslessWriter::write(const cv::Mat& frame) {
  if (frame.size() != size_ || frame.channels() != (colour_ ? 3 : 1) || frame.depth() != CV_8U)
    throw std::invalid_argument(name_ + ": frame " + std::to_string(frames_) +
                                " does not match the video's size or channels");
  writer_.write(frame);
  ++frames_;
}

void LosslessWriter::close() {
  writer_.release();
}

}  // namespace ps::tracking
