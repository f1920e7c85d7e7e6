// Search boxes around where markers were, each searched by a back end (detector.hpp,
// DetectorConfig::regions).
#include <algorithm>
#include <cmath>
#include <map>

#include "tracking/corner_refine.hpp"
#include "tracking/detector.hpp"

namespace ps::tracking {

namespace {

cv::Point2d centre(const Detection& d) {
  return 0.25 * (d.corners[0] + d.corners[1] + d.corners[2] + d.corners[3]);
}

// How far a square marker looks turned out of the image plane, from its quad alone: the ratio
// of the singular values of the map taking the square's two mid-lines to the quad's is the
// cosine of the tilt (perspective aside).
double apparentTiltDeg(const Detection& d) {
  const auto& c = d.corners;
  const cv::Point2d u = 0.5 * ((c[1] + c[2]) - (c[0] + c[3]));
  const cv::Point2d v = 0.5 * ((c[3] + c[2]) - (c[0] + c[1]));
  // Singular values of [u v] from the trace and determinant of its Gram matrix.
  const double a = u.dot(u), b = u.dot(v), e = v.dot(v);
  const double mean = 0.5 * (a + e), root = std::sqrt(0.25 * (a - e) * (a - e) + b * b);
  const double big = mean + root, small = std::max(mean - root, 0.0);
  if (big <= 0) return 90.0;
  return std::acos(std::clamp(std::sqrt(small / big), 0.0, 1.0)) * 180.0 / M_PI;
}

class RegionDetector final : public Detector {
 public:
  explicit RegionDetector(const DetectorConfig& c) : config_(c) {
    DetectorConfig base = c;
    base.regions = false;
    base.ids.clear();  // filtered here, after merging
    auto make = [&](const DetectorConfig& x) {
      return x.backend == Backend::kAprilTag ? makeAprilTagDetector(x) : makeArucoDetector(x);
    };
    finder_ = make(base);
    if (c.backend == Backend::kAprilTag && c.expectedSearchDecimate > 0 &&
        c.expectedSearchDecimate != c.decimate) {
      DetectorConfig coarse = base;
      coarse.decimate = c.expectedSearchDecimate;
      expectedFinder_ = make(coarse);
    }
    coarseRefiner_ = c.coarseRegionPx > 0 ? make(base) : nullptr;
    base.decimate = 1.0;
    refiner_ = make(base);
  }

  std::string name() const override { return finder_->name() + " + regions"; }
  void expect(const std::vector<Detection>& markers) override {
    if (config_.expectedSearchEvery > 0) expectedNext_ = markers;
    expectedIdsNext_.clear();
    for (const auto& d : markers) expectedIdsNext_.push_back(d.id);
  }
  Backend backend() const override { return finder_->backend(); }

  std::vector<Detection> detect(const cv::Mat& image) override {
    const cv::Mat grey = toGrey(image);
    const cv::Rect frame(0, 0, grey.cols, grey.rows);
    if (grey.size() != lastSize_) {
      last_.clear();
      previous_.clear();
      expectedBefore_.clear();
      lastSize_ = grey.size();
    }
    ++frameNo_;
    std::vector<Detection> found;
    // 1. Where each marker was, moved on by its last motion; and where markers not seen last
    // frame are expected (moved on by how their expectation moved).
    std::vector<SearchBox> boxes, coarseBoxes;
    auto addBox = [&](const Detection& d, const std::map<int, Detection>& before) {
      Detection p = d;
      const auto prev = before.find(d.id);
      if (prev != before.end()) {
        const cv::Point2d motion = centre(d) - centre(prev->second);
        for (auto& c : p.corners) c += motion;
      }
      const bool inLargeSet = largeSet(d.id) && side(d) >= config_.coarseRegionPx;
      (inLargeSet ? coarseBoxes : boxes).push_back({box(p, frame) | box(d, frame), 1});
    };
    for (const auto& [id, d] : last_) addBox(d, previous_);
    std::map<int, Detection> expected;
    for (const auto& d : expectedNext_)
      if (wanted(d.id) && !last_.count(d.id) && box(d, frame).width >= 16 &&
          box(d, frame).height >= 16)
        expected[d.id] = d;
    expectedNext_.clear();
    const std::vector<int> expectedIds = std::move(expectedIdsNext_);
    expectedIdsNext_.clear();
    for (const auto& [id, d] : expected) addBox(d, expectedBefore_);
    expectedBefore_ = expected;
    // Few or small markers first, at full resolution; then the large sets' boxes, at the
    // frame's decimation where enough of their markers are in one box (what the first pass
    // found there already is kept).
    for (const auto& b : mergeBoxes(boxes)) addFrom(grey, b, found, false);
    for (const auto& b : mergeBoxes(coarseBoxes))
      addFrom(grey, b, found, b.markers >= config_.coarseRegionMarkers);
    // 2. The whole frame when something expected is missing: an id outside the rigid sets, or
    // a whole set (every `searchEvery` frames); a set with some markers in view is searched for
    // the rest only every `setSearchEvery` frames (a face turning into view, a hand lifting).
    auto seen = [&](int id) {
      return std::any_of(found.begin(), found.end(),
                         [&](const Detection& d) { return d.id == id; });
    };
    // Missing and expected in the frame (some of its markers' boxes were searched above): the
    // whole frame is searched less often for it.
    auto isExpected = [&](int id) { return expected.count(id) > 0; };
    // Missing and expected anywhere (a pose carries it): the coarse whole-frame search will do.
    auto isCarried = [&](int id) {
      return std::find(expectedIds.begin(), expectedIds.end(), id) != expectedIds.end();
    };
    bool missing = config_.ids.empty(), partial = false, unexpected = config_.ids.empty();
    bool carried = false;
    for (int id : config_.ids) {
      const auto set = std::find_if(config_.sets.begin(), config_.sets.end(), [&](const auto& g) {
        return std::find(g.begin(), g.end(), id) != g.end();
      });
      if (set == config_.sets.end()) {
        missing |= !seen(id);
        unexpected |= !seen(id) && !isExpected(id);
      } else if (!seen(id)) {
        if (std::any_of(set->begin(), set->end(), seen)) {
          partial = true;
        } else {
          missing = true;
          unexpected |= std::none_of(set->begin(), set->end(), isExpected);
          carried |= std::any_of(set->begin(), set->end(), isCarried);
        }
      }
    }
    const int since = frameNo_ - lastSearch_;
    const int every = unexpected ? config_.searchEvery : config_.expectedSearchEvery;
    if ((missing && since >= every) || (partial && since >= config_.setSearchEvery)) {
      lastSearch_ = frameNo_;
      // A missing set carried by a pose, no partial set to complete at full detail: the
      // coarse search, with one at `decimate` every expectedFullSearchEvery frames for what it
      // misses (a set missing without a pose, the tool under the same hand, is looked for
      // by both).
      bool coarse = expectedFinder_ && missing && carried && !partial &&
                    frameNo_ - lastFullSearch_ < config_.expectedFullSearchEvery;
      std::vector<Detection> candidates = (coarse ? *expectedFinder_ : *finder_).detect(grey);
      // The coarse search only says whether something came back: what it saw, the search at
      // `decimate` takes in this frame (a tool found coarsely showed two of its three faces,
      // and its tip was 14 mm off in that frame).
      if (coarse && std::any_of(candidates.begin(), candidates.end(), [&](const Detection& d) {
            return wanted(d.id) && !known(found, d);
          })) {
        coarse = false;
        candidates = finder_->detect(grey);
      }
      if (!coarse) lastFullSearch_ = frameNo_;
      std::vector<SearchBox> fresh;
      for (const auto& d : candidates) {
        if (!wanted(d.id) || known(found, d)) continue;
        fresh.push_back({box(d, frame), 1});
      }
      for (const auto& b : mergeBoxes(fresh)) addFrom(grey, b, found, false);
    }
    finishDetections(config_, found);
    previous_.clear();
    for (const auto& [id, d] : last_)
      if (std::any_of(found.begin(), found.end(),
                      [want = id](const Detection& x) { return x.id == want; }))
        previous_[id] = d;
    last_.clear();
    std::map<int, int> count;
    for (const auto& d : found) ++count[d.id];
    for (const auto& d : found)
      if (count[d.id] == 1) last_[d.id] = d;  // an id seen twice is not followed
    if (config_.refineLoneSetMarkers) refineLoneMarkers(grey, count, found);
    return found;
  }

 private:
  bool wanted(int id) const {
    return config_.ids.empty() ||
           std::find(config_.ids.begin(), config_.ids.end(), id) != config_.ids.end();
  }
  static bool known(const std::vector<Detection>& found, const Detection& d) {
    return std::any_of(found.begin(), found.end(), [&](const Detection& x) {
      return x.id == d.id && cv::norm(centre(x) - centre(d)) < 4.0;
    });
  }
  // The corners' bounding box in the image (x0, y0, x1, y1).
  static cv::Vec4d extent(const Detection& d) {
    double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
    for (const auto& c : d.corners) {
      x0 = std::min(x0, c.x), x1 = std::max(x1, c.x);
      y0 = std::min(y0, c.y), y1 = std::max(y1, c.y);
    }
    return {x0, y0, x1, y1};
  }
  // The marker's larger extent in the image (px).
  static double side(const Detection& d) {
    const cv::Vec4d e = extent(d);
    return std::max(e[2] - e[0], e[3] - e[1]);
  }
  cv::Rect box(const Detection& d, const cv::Rect& frame) const {
    const cv::Vec4d e = extent(d);
    const double m = config_.regionMargin * side(d) + 8.0;
    const cv::Rect r(cv::Point(int(std::floor(e[0] - m)), int(std::floor(e[1] - m))),
                     cv::Point(int(std::ceil(e[2] + m)) + 1, int(std::ceil(e[3] + m)) + 1));
    return r & frame;
  }
  // A box to search and how many markers were expected in it.
  struct SearchBox {
    cv::Rect rect;
    int markers = 1;
  };
  static std::vector<SearchBox> mergeBoxes(std::vector<SearchBox> boxes) {
    bool merged = true;
    while (merged) {
      merged = false;
      for (std::size_t i = 0; i < boxes.size() && !merged; ++i)
        for (std::size_t j = i + 1; j < boxes.size() && !merged; ++j)
          if ((boxes[i].rect & boxes[j].rect).area() > 0) {
            boxes[i].rect |= boxes[j].rect;
            boxes[i].markers += boxes[j].markers;
            boxes.erase(boxes.begin() + std::ptrdiff_t(j));
            merged = true;
          }
    }
    std::erase_if(boxes,
                  [](const SearchBox& r) { return r.rect.width < 16 || r.rect.height < 16; });
    return boxes;
  }
  // Whether `id` belongs to a rigid set large enough for a coarse search.
  bool largeSet(int id) const {
    if (!coarseRefiner_) return false;
    return std::any_of(config_.sets.begin(), config_.sets.end(), [&](const auto& set) {
      return int(set.size()) >= config_.coarseRegionMarkers &&
             std::find(set.begin(), set.end(), id) != set.end();
    });
  }
  void addFrom(const cv::Mat& grey, const SearchBox& searchBox, std::vector<Detection>& found,
               bool coarse) {
    const cv::Rect& r = searchBox.rect;
    Detector& search = coarse ? *coarseRefiner_ : *refiner_;
    for (auto d : search.detect(grey(r))) {
      for (auto& c : d.corners) c += cv::Point2d(r.x, r.y);
      if (wanted(d.id) && !known(found, d)) found.push_back(d);
    }
  }

  // The search boxes follow the detector's own corners (last_); only what is returned is refined.
  void refineLoneMarkers(const cv::Mat& grey, std::map<int, int>& count,
                         std::vector<Detection>& found) {
    for (const auto& set : config_.sets) {
      Detection* lone = nullptr;
      int seenInSet = 0;
      for (auto& d : found)
        if (std::find(set.begin(), set.end(), d.id) != set.end()) {
          ++seenInSet;
          lone = &d;
        }
      if (seenInSet == 1 && count[lone->id] == 1 &&
          apparentTiltDeg(*lone) <= config_.refineLoneMaxTiltDeg)
        cornerRefiner_.refine(grey, *lone);
    }
  }

  DetectorConfig config_;
  CornerRefiner cornerRefiner_{config_.family};
  std::unique_ptr<Detector> finder_, refiner_, coarseRefiner_;
  std::unique_ptr<Detector> expectedFinder_;  // the whole frame at expectedSearchDecimate
  std::map<int, Detection> last_, previous_;
  std::vector<Detection> expectedNext_;      // for the next detect() only
  std::map<int, Detection> expectedBefore_;  // what the last detect() expected
  std::vector<int> expectedIdsNext_;         // ids expected by the next detect(), any setting
  cv::Size lastSize_;
  long long frameNo_ = 0, lastSearch_ = -1000000, lastFullSearch_ = -1000000;
};

}  // namespace

std::unique_ptr<Detector> makeRegionDetector(const DetectorConfig& config) {
  return std::make_unique<RegionDetector>(config);
}

}  // namespace ps::tracking
