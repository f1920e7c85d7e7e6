#pragma once
// A pose polished over point correspondences by Levenberg-Marquardt with analytic derivatives.
//
// Why not cv::solvePnPRefineLM: it runs OpenCV's general solver (its C matrices, a Rodrigues
// Jacobian, a fixed stopping rule), about 120 us for one marker's four corners and 195 us for a
// board's 36 on this project's machine, and a marker set's pose polishes two candidates a frame
// (docs/TRACKING.md, "Where a frame's time goes"). This one stops when a step no longer changes
// the pose at double precision and reaches the same minimum; the single-marker path keeps
// OpenCV's solver so that old recordings replay bit for bit.
#include <opencv2/core.hpp>
#include <vector>

#include "tracking/calibration.hpp"
#include "tracking/pose.hpp"

namespace ps::tracking {

// Polishes `pose` (body to camera) so that the body-frame points `object` project onto
// `image`, with the calibration's distortion (up to the 8 rational coefficients; a model with
// thin-prism or tilt terms goes to OpenCV's solver). Returns the RMS reprojection error (px),
// or infinity when the solver fails, a point ends behind the camera or the pose is not finite;
// `pose` is then unspecified.
double refinePose(const std::vector<cv::Point3d>& object, const std::vector<cv::Point2d>& image,
                  const CameraCalibration& calibration, Pose& pose);

}  // namespace ps::tracking
