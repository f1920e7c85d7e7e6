#pragma once
// Camera calibrations in OpenCV's YAML format (cv::FileStorage): `camera_matrix` (3x3),
// `distortion_coefficients` (1xN or Nx1, N in {4, 5, 8, 12, 14}), `image_width` and
// `image_height` (optional: some files omit them), `avg_reprojection_error` (optional).
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace ps::tracking {

struct CameraCalibration {
  cv::Matx33d K = cv::Matx33d::eye();
  cv::Mat distortion = cv::Mat::zeros(1, 5, CV_64F);  // 1xN, double
  cv::Size imageSize{0, 0};                           // 0x0 when the file did not say
  double rms = -1;                                    // avg_reprojection_error, -1 unknown
  std::string source = "<memory>";                    // file it came from (messages)

  // A pinhole camera without distortion.
  static CameraCalibration pinhole(double fx, double fy, double cx, double cy, cv::Size size);

  // The calibration for frames of `size`: intrinsics scaled by the ratio of the sizes with the
  // pixel-centre convention kept (c' = (c + 0.5) * s - 0.5). A calibration of unknown size is
  // taken to be for `size`. Throws core::InputError naming the file when the aspect ratios
  // differ by more than 1 % (a crop, not a scale: the calibration does not apply).
  CameraCalibration forImageSize(cv::Size size) const;

  // Throws core::InputError naming `source` for a singular or non-finite matrix, or bad
  // distortion coefficients.
  void validate() const;
};

// Throws core::InputError "FILE: what is wrong" for a missing, unreadable or malformed file.
CameraCalibration loadCalibration(const std::filesystem::path& path);
// The same from a file's text (YAML with its %YAML header, XML or JSON; `name` in messages).
CameraCalibration parseCalibration(const std::string& text, const std::string& name);
// Writes image_width/height (when known), camera_matrix, distortion_coefficients (1xN) and
// avg_reprojection_error (when known), plus any `comment`, as YAML whatever the extension;
// atomic (a temporary file renamed). Throws on I/O errors.
void saveCalibration(const CameraCalibration& calibration, const std::filesystem::path& path,
                     const std::string& comment = "");

}  // namespace ps::tracking
