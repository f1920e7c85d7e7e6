#pragma once
// Pieces the synthetic renderer's files share (synth.cpp: scene, single markers, truth;
// synth_bodies.cpp: boards, tool solids and hands). Not part of the library's interface.
#include <Eigen/Core>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "tracking/calibration.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking::synth_detail {

inline constexpr double kDeg = std::numbers::pi / 180.0;

inline cv::Matx33d toCv(const Eigen::Matrix3d& m) {
  cv::Matx33d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
  return r;
}

// Homography from the marker plane (z = 0, metres) to pixels.
inline cv::Matx33d planeHomography(const CameraCalibration& cam, const Pose& pose) {
  Eigen::Matrix3d M;
  M.col(0) = pose.R.col(0);
  M.col(1) = pose.R.col(1);
  M.col(2) = pose.t;
  return cam.K * toCv(M);
}

// The card texture (marker cells plus `margin` white cells) in cells -> marker plane metres.
inline cv::Matx33d cardToPlane(const FamilyInfo& info, int margin, double size) {
  const double c = size / info.edgeCells;
  const double mid = margin + info.edgeOffset + 0.5 * info.edgeCells;
  return {c, 0, -mid * c, 0, -c, mid * c, 0, 0, 1};
}

inline cv::Mat makeCard(const std::string& family, int id, int margin) {
  cv::Mat card;
  cv::copyMakeBorder(markerCells(family, id), card, margin, margin, margin, margin,
                     cv::BORDER_CONSTANT, cv::Scalar(255));
  // Paper is not perfectly white, ink not perfectly black.
  card.convertTo(card, CV_8U, (235.0 - 25.0) / 255.0, 25.0);
  return card;
}

}  // namespace ps::tracking::synth_detail
