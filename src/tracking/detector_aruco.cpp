// The OpenCV aruco back end (contrib 4.6 API: aruco::detectMarkers + DetectorParameters).
#include <algorithm>
#include <cmath>
#include <opencv2/aruco.hpp>

#include "tracking/detector.hpp"

namespace ps::tracking {

namespace {

class ArucoDetector final : public Detector {
 public:
  explicit ArucoDetector(const DetectorConfig& c) : config_(c), info_(familyInfo(c.family)) {
    dictionary_ = cv::aruco::getPredefinedDictionary(info_.arucoDictionary);
    params_ = cv::aruco::DetectorParameters::create();
    switch (c.arucoRefinement) {
      case ArucoRefinement::kNone:
        params_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
        break;
      case ArucoRefinement::kSubpix:
        params_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
        break;
      case ArucoRefinement::kContour:
        params_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_CONTOUR;
        break;
      case ArucoRefinement::kAprilTag:
        params_->cornerRefinementMethod = cv::aruco::CORNER_REFINE_APRILTAG;
        params_->aprilTagQuadDecimate = float(c.decimate);
        params_->aprilTagQuadSigma = float(c.blurSigma);
        break;
    }
  }

  std::string name() const override {
    return "aruco " + config_.family + " " + toString(config_.arucoRefinement);
  }
  Backend backend() const override { return Backend::kAruco; }

  std::vector<Detection> detect(const cv::Mat& image) override {
    const cv::Mat grey = toGrey(image);
    // OpenCV 4.6's AprilTag refinement first decimates by aprilTagQuadDecimate and throws an
    // assertion (resize to an empty size) for an image with a 1-pixel side; as in the AprilTag
    // back end, images under 3 x ceil(decimate) pixels on a side (no marker fits) are not searched.
    if (config_.arucoRefinement == ArucoRefinement::kAprilTag &&
        std::min(grey.cols, grey.rows) < 3 * int(std::ceil(config_.decimate)))
      return {};
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(grey, dictionary_, corners, ids, params_);
    // The AprilTag refinement keeps AprilTag's pixel convention (centres at +0.5).
    const double shift = config_.arucoRefinement == ArucoRefinement::kAprilTag ? 0.5 : 0.0;
    std::vector<Detection> out;
    out.reserve(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      Detection d;
      d.id = ids[i];
      for (int k = 0; k < 4; ++k) {
        const cv::Point2f& p = corners[i][std::size_t((k + info_.arucoQuarterTurns) % 4)];
        d.corners[std::size_t(k)] = {double(p.x) - shift, double(p.y) - shift};
      }
      out.push_back(d);
    }
    finishDetections(config_, out);
    return out;
  }

 private:
  DetectorConfig config_;
  FamilyInfo info_;
  cv::Ptr<cv::aruco::Dictionary> dictionary_;
  cv::Ptr<cv::aruco::DetectorParameters> params_;
};

}  // namespace

std::unique_ptr<Detector> makeArucoDetector(const DetectorConfig& config) {
  return std::make_unique<ArucoDetector>(config);
}

}  // namespace ps::tracking
