#pragma once
// The pose of a rigid set of markers (marker_layout.hpp: the planet board, a tool solid) from
// every visible marker's corners together.
//
// Seeds: the planar candidates (markerPoseSeeds: IPPE_SQUARE, and SQPNP on the largest) of the
// three largest markers in the image, carried to the body's frame through each marker's place in
// the layout, scored by the reprojection RMS of every visible corner. The best seed, and the best
// one turned more than 10 degrees away from it (its flip), are polished by Levenberg-Marquardt
// over all corners (pose_refine.hpp). With several markers seen at different places the wrong
// planar candidate of one marker reprojects the others badly, so the flip is decided by the
// whole board. When the two polished poses score within `ambiguityRatio` (one face of a solid
// seen alone), the one that leaves fewer of the layout's markers unread though they would face
// the camera in the image wins; if that ties, the one nearer the previous pose (continuity), as
// for a single marker (pose.hpp).
#include <span>
#include <string>
#include <vector>

#include "tracking/calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking {

struct BodyPoseResult {
  bool valid = false;
  Pose pose;         // body -> camera
  double rms = 0;    // reprojection RMS over every used corner (px)
  double ratio = 0;  // the best turned-away alternative's RMS / rms (inf: none)
  bool byContinuity = false;
  bool byVisibility = false;  // decided by which other markers each candidate says were in view
  std::vector<int> ids;       // markers whose corners gave the pose, ascending
  std::string note;           // why some detections were not used
};

// `detections` may hold ids outside the layout or markers of another family (ignored). An id seen
// more than once is not used (which of them is the board's cannot be told from one frame).
BodyPoseResult solveBodyPose(const MarkerLayout& layout, std::span<const Detection> detections,
                             const CameraCalibration& calibration, const Pose* previous,
                             double ambiguityRatio);

// Image positions of every corner of the layout's markers for a body pose (with distortion).
std::vector<std::array<cv::Point2d, 4>> projectLayout(const MarkerLayout& layout, const Pose& body,
                                                      const CameraCalibration& calibration);

}  // namespace ps::tracking
