#include "tracking/detector.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/input_error.hpp"
#include "core/named_values.hpp"

namespace ps::tracking {

namespace {
constexpr core::NameTable<ArucoRefinement, 4> kRefinements{
    "aruco corner refinement",
    {{{ArucoRefinement::kNone, "none"},
      {ArucoRefinement::kSubpix, "subpix"},
      {ArucoRefinement::kContour, "contour"},
      {ArucoRefinement::kAprilTag, "apriltag"}}}};
}  // namespace

std::string toString(ArucoRefinement r) {
  return kRefinements.nameOf(r);
}

ArucoRefinement arucoRefinementFromString(const std::string& s) {
  return kRefinements.parse(s);
}

void DetectorConfig::validate() const {
  const FamilyInfo info = familyInfo(family);
  for (int id : ids)
    if (id < 0 || id >= info.markerCount)
      throw core::InputError("marker id " + std::to_string(id) + " is not in " + family + " (0.." +
                             std::to_string(info.markerCount - 1) + ")");
  if (!std::isfinite(decimate) || decimate < 1.0 || decimate > 8.0)
    throw core::InputError("AprilTag decimate = " + std::to_string(decimate) + " is not in [1, 8]");
  if (!std::isfinite(blurSigma) || std::abs(blurSigma) > 10.0)
    throw core::InputError("AprilTag blur sigma = " + std::to_string(blurSigma) +
                           " is not in [-10, 10]");
  if (!std::isfinite(sharpening) || sharpening < 0 || sharpening > 10)
    throw core::InputError("AprilTag sharpening = " + std::to_string(sharpening) +
                           " is not in [0, 10]");
  if (maxHamming < 0 || maxHamming > 3)
    throw core::InputError("max hamming = " + std::to_string(maxHamming) + " is not in 0..3");
  if (minContrast < 0 || minContrast > 255)
    throw core::InputError("AprilTag min contrast = " + std::to_string(minContrast) +
                           " is not in 0..255");
  if (searchEvery < 1 || searchEvery > 1000)
    throw core::InputError("search every = " + std::to_string(searchEvery) + " is not in 1..1000");
  if (expectedSearchEvery < 0 || expectedSearchEvery > 1000)
    throw core::InputError("expected search every = " + std::to_string(expectedSearchEvery) +
                           " is not in 0..1000");
  if (expectedSearchDecimate != 0 && (!std::isfinite(expectedSearchDecimate) ||
                                      expectedSearchDecimate < 1.0 || expectedSearchDecimate > 8.0))
    throw core::InputError("expected search decimate = " + std::to_string(expectedSearchDecimate) +
                           " is not 0 or in [1, 8]");
  if (expectedFullSearchEvery < 1 || expectedFullSearchEvery > 1000)
    throw core::InputError("expected full search every = " +
                           std::to_string(expectedFullSearchEvery) + " is not in 1..1000");
  if (setSearchEvery < 1 || setSearchEvery > 1000)
    throw core::InputError("set search every = " + std::to_string(setSearchEvery) +
                           " is not in 1..1000");
  if (!(coarseRegionPx >= 0) || !std::isfinite(coarseRegionPx))
    throw core::InputError("coarse region size = " + std::to_string(coarseRegionPx) +
                           " px is not >= 0");
  if (coarseRegionMarkers < 1)
    throw core::InputError("coarse region markers = " + std::to_string(coarseRegionMarkers) +
                           " is not >= 1");
  if (!std::isfinite(regionMargin) || regionMargin < 0.1 || regionMargin > 5)
    throw core::InputError("region margin = " + std::to_string(regionMargin) +
                           " is not in [0.1, 5]");
  if (threads < 1 || threads > 64)
    throw core::InputError("detector threads = " + std::to_string(threads) + " is not in 1..64");
}

cv::Mat toGrey(const cv::Mat& image) {
  if (image.empty()) throw core::InputError("empty image");
  if (image.depth() != CV_8U)
    throw core::InputError("image depth " + std::to_string(image.depth()) + " is not 8-bit");
  if (image.channels() == 1) return image;
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4)
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  else
    throw core::InputError("image with " + std::to_string(image.channels()) + " channels");
  return grey;
}

void finishDetections(const DetectorConfig& config, std::vector<Detection>& d) {
  for (auto& x : d) x.family = config.family;
  if (!config.ids.empty()) {
    std::erase_if(d, [&](const Detection& x) {
      return std::find(config.ids.begin(), config.ids.end(), x.id) == config.ids.end();
    });
  }
  std::sort(d.begin(), d.end(), [](const Detection& a, const Detection& b) {
    if (a.id != b.id) return a.id < b.id;
    if (a.corners[0].y != b.corners[0].y) return a.corners[0].y < b.corners[0].y;
    return a.corners[0].x < b.corners[0].x;
  });
}

namespace {

class MultiFamilyDetector final : public Detector {
 public:
  MultiFamilyDetector(std::vector<std::unique_ptr<Detector>> parts,
                      std::vector<std::string> families)
      : parts_(std::move(parts)), families_(std::move(families)) {}
  std::string name() const override {
    std::string n;
    for (const auto& p : parts_) n += (n.empty() ? "" : " | ") + p->name();
    return n;
  }
  // The first family's back end (the others are named in name()).
  Backend backend() const override { return parts_.front()->backend(); }
  std::vector<Detection> detect(const cv::Mat& image) override {
    const cv::Mat grey = toGrey(image);  // once for every family
    std::vector<Detection> all;
    for (const auto& p : parts_) {
      std::vector<Detection> found = p->detect(grey);
      all.insert(all.end(), std::make_move_iterator(found.begin()),
                 std::make_move_iterator(found.end()));
    }
    return all;
  }
  void expect(const std::vector<Detection>& markers) override {
    for (std::size_t i = 0; i < parts_.size(); ++i) {
      std::vector<Detection> mine;
      for (const auto& m : markers)
        if (m.family.empty() || m.family == families_[i]) mine.push_back(m);
      parts_[i]->expect(mine);
    }
  }

 private:
  std::vector<std::unique_ptr<Detector>> parts_;
  std::vector<std::string> families_;  // parts_[i]'s family
};

}  // namespace

std::unique_ptr<Detector> makeDetector(const std::vector<DetectorConfig>& families) {
  if (families.empty()) throw core::InputError("no marker family to detect");
  for (std::size_t i = 0; i < families.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (families[i].family == families[k].family)
        throw core::InputError("marker family " + families[i].family +
                               " is given twice to one detector");
  if (families.size() == 1) return makeDetector(families.front());
  std::vector<std::unique_ptr<Detector>> parts;
  std::vector<std::string> names;
  for (const auto& c : families) {
    parts.push_back(makeDetector(c));
    names.push_back(c.family);
  }
  return std::make_unique<MultiFamilyDetector>(std::move(parts), std::move(names));
}

std::unique_ptr<Detector> makeDetector(const DetectorConfig& config) {
  config.validate();
  const FamilyInfo info = familyInfo(config.family);
  Backend b = config.backend;
  if (b == Backend::kAuto) b = info.apriltag ? Backend::kAprilTag : Backend::kAruco;
  if (b == Backend::kAprilTag && !info.apriltag)
    throw core::InputError("the AprilTag library cannot read " + config.family +
                           " (use --detector aruco, or an AprilTag family such as tag36h11)");
  if (b == Backend::kAruco && info.arucoDictionary < 0)
    throw core::InputError("OpenCV's aruco module has no dictionary for " + config.family +
                           " (use --detector apriltag)");
  DetectorConfig c = config;
  c.backend = b;
  if (c.regions) return makeRegionDetector(c);
  return b == Backend::kAprilTag ? makeAprilTagDetector(c) : makeArucoDetector(c);
}

}  // namespace ps::tracking
