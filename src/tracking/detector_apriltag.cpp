// The AprilTag C library back end (3.3; Debian splits it into apriltag and apriltag-utils).
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/input_error.hpp"
#include "tracking/apriltag_families.hpp"
#include "tracking/detector.hpp"

namespace ps::tracking {

namespace {

// One family object per family and number of correctable bits, shared by every detector of the
// process. The library builds a family's decoding table when the family is first added to a
// detector (tag36h11 at 2 bits: over a million entries, tens of MB) and frees it when a
// detector holding the family is destroyed; a detector per setting change or test case rebuilt
// it each time (under the sanitizers, whose allocator maps every large block afresh, most of a
// tracking test's time, docs/CI.md). Detection only reads the table, so threads may share it.
// The families are never freed (reachable from here to the end, so no leak is reported).
void addSharedFamily(apriltag_detector_t* td, const std::string& name, int bits) {
  static auto* const families = new std::map<std::pair<std::string, int>, apriltag_family_t*>;
  static std::mutex lock;
  const std::lock_guard<std::mutex> hold(lock);
  apriltag_family_t*& family = (*families)[{name, bits}];
  if (!family) {
    detail::FamilyPtr made = detail::createAprilTagFamily(name);
    if (!made) {
      families->erase({name, bits});
      throw core::InputError("the AprilTag library cannot read " + name);
    }
    family = made.release();
  }
  apriltag_detector_add_family_bits(td, family, bits);  // builds the table the first time only
}

class AprilTagDetector final : public Detector {
 public:
  explicit AprilTagDetector(const DetectorConfig& c) : config_(c) {
    td_ = apriltag_detector_create();
    if (!td_) throw std::runtime_error("apriltag_detector_create failed");
    try {
      addSharedFamily(td_, c.family, c.maxHamming);
    } catch (...) {
      apriltag_detector_destroy(td_);
      throw;
    }
    td_->quad_decimate = float(c.decimate);
    td_->quad_sigma = float(c.blurSigma);
    td_->refine_edges = c.refineEdges;
    td_->decode_sharpening = c.sharpening;
    td_->nthreads = c.threads;
    td_->qtp.min_white_black_diff = c.minContrast;
  }
  ~AprilTagDetector() override {
    // Not apriltag_detector_remove_family (or destroy with the family listed): both free the
    // shared family's table.
    zarray_clear(td_->tag_families);
    apriltag_detector_destroy(td_);
  }
  AprilTagDetector(const AprilTagDetector&) = delete;
  AprilTagDetector& operator=(const AprilTagDetector&) = delete;

  std::string name() const override {
    char d[16];
    std::snprintf(d, sizeof d, "%g", config_.decimate);
    return "apriltag " + config_.family + " d" + d;
  }
  Backend backend() const override { return Backend::kAprilTag; }

  std::vector<Detection> detect(const cv::Mat& image) override {
    const cv::Mat grey = toGrey(image);
    // The AprilTag library (3.3) crashes (SIGSEGV, or SIGFPE at decimate 1.5) when the image it
    // searches for quads - decimated by quad_decimate - is under 3 pixels on a side (a 1x1
    // frame, a 320x2 sliver, 8x8 at decimate 4). 3 x ceil(decimate) pixels is safe for every size
    // and decimate tried (StressTracking.AprilTagSurvivesTinyImagesAtAnyDecimate); no marker fits
    // in an image that small anyway.
    if (std::min(grey.cols, grey.rows) < 3 * int(std::ceil(config_.decimate))) return {};
    image_u8_t im{grey.cols, grey.rows, int(grey.step[0]), grey.data};
    zarray_t* found = apriltag_detector_detect(td_, &im);
    std::vector<Detection> out;
    out.reserve(std::size_t(zarray_size(found)));
    for (int i = 0; i < zarray_size(found); ++i) {
      apriltag_detection_t* a = nullptr;
      zarray_get(found, i, &a);
      Detection d;
      d.id = a->id;
      d.hamming = a->hamming;
      d.decisionMargin = a->decision_margin;
      // AprilTag lists the corners counter-clockwise from the canonical image's bottom-left
      // (p[0] = BL, p[1] = BR, p[2] = TR, p[3] = TL) with pixel centres at +0.5.
      static constexpr int kFromAprilTag[4] = {3, 2, 1, 0};
      for (int k = 0; k < 4; ++k) {
        const double* p = a->p[kFromAprilTag[k]];
        d.corners[std::size_t(k)] = {p[0] - 0.5, p[1] - 0.5};
      }
      out.push_back(d);
    }
    apriltag_detections_destroy(found);
    finishDetections(config_, out);
    return out;
  }

 private:
  DetectorConfig config_;
  apriltag_detector_t* td_ = nullptr;
};

}  // namespace

std::unique_ptr<Detector> makeAprilTagDetector(const DetectorConfig& config) {
  return std::make_unique<AprilTagDetector>(config);
}

}  // namespace ps::tracking
