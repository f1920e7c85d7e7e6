#pragma once
// The last step of an AR frame when something real is in front of the planet (issue 42): the
// camera image shown over the rendered view where a soft mask says, an alpha blend
// view·(1 - mask) + camera·mask. The mask comes from tracking::HandMasker (tracking/hand_mask.hpp).
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <span>

#include "terrain/camera.hpp"

namespace ps::render {

// `view`: the rendered AR frame (BGR 8-bit); `camera`: the image it was drawn over (BGR or grey,
// the same size); `mask`: CV_32F in [0, 1], the same size (empty: nothing to do). Returns the
// blended frame (the view itself, unchanged, when the mask is empty or all zero). Throws
// std::invalid_argument for mismatched sizes or types.
cv::Mat composeOcclusion(const cv::Mat& view, const cv::Mat& camera, const cv::Mat& mask);

// The hand mask sees anything that is not the board, the tool included; the tool has its own,
// exact occlusion (the depth pass, render/occluder_pass.hpp), which also knows when the tool is
// behind the planet. So the mask is cleared over the tool's projected triangles (planet frame,
// planet metres, as `camera` sees them) grown by `marginPx`, where the depth pass decides alone.
void clearToolFromMask(cv::Mat& mask, const terrain::Camera& camera,
                       std::span<const Eigen::Vector3d> toolTriangles, int marginPx = 3);

// The AR frame's last step where a hand may be in front of the planet, one path for the live
// loop, the AR recorder and `bench frame` (the mask from replay::HandOcclusion): `mask` cleared
// over the tool (clearToolFromMask), then, where it still holds a pixel over 0.5, `view` with
// the camera image blended over it (composeOcclusion). Empty when nothing is in front: the view
// stands as rendered.
cv::Mat occludeByHand(const cv::Mat& view, const cv::Mat& camera, cv::Mat& mask,
                      const terrain::Camera& cam, std::span<const Eigen::Vector3d> toolTriangles);

}  // namespace ps::render
