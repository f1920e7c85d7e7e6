#pragma once
// Marker detection behind one interface, with two back ends: OpenCV's aruco module (4.6 API)
// and the AprilTag C library (3.3). Whatever the back end, corners come out
//   * in the order TL, TR, BR, BL of the marker's canonical image (marker_family.hpp), and
//   * in OpenCV's pixel convention (pixel centres at integer coordinates; AprilTag's +0.5 is
//     taken off),
// so poses, calibrations and tests never know which library found a marker.
#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/marker_family.hpp"

namespace ps::tracking {

struct Detection {
  // The family the marker was read as (the config's family name): ids are only unique within
  // a family, so a marker is known by (family, id). Empty: not said (corners made elsewhere).
  std::string family;
  int id = -1;
  std::array<cv::Point2d, 4> corners;  // TL, TR, BR, BL
  int hamming = 0;                     // bits corrected (AprilTag), 0 for aruco
  double decisionMargin = 0;           // AprilTag's decision margin, 0 for aruco
};

enum class ArucoRefinement { kNone, kSubpix, kContour, kAprilTag };
std::string toString(ArucoRefinement r);
ArucoRefinement arucoRefinementFromString(const std::string& s);  // InputError

struct DetectorConfig {
  std::string family = "tag36h11";
  Backend backend = Backend::kAuto;  // auto: AprilTag for tag* families, aruco for DICT_*
  std::vector<int> ids;              // keep only these ids (empty: every id of the family)

  // AprilTag back end.
  double decimate = 2.0;     // quad_decimate: quads are found on a 1/decimate image; the edges are
                             // then refined on the full image (refineEdges)
  double blurSigma = 0.0;    // quad_sigma
  bool refineEdges = true;   // refine_edges
  double sharpening = 0.25;  // decode_sharpening
  int maxHamming = 2;        // bits corrected when decoding (<= 2 for tag36h11; memory grows fast)
  // min_white_black_diff: quads are only looked for where the grey range over a small
  // neighbourhood (about 12 x 12 pixels of the decimated image) reaches this. The library's 5 lets
  // a flat area's noise (sigma 1.5 already spans about 9 levels there) through to segmentation,
  // whose clusters then cost most of a search. A marker's black and white differ by far more
  // (the synthetic scenes' dimmest, the real photographs); 0-255.
  int minContrast = 20;
  int threads = 1;  // nthreads (1: deterministic and on one core)

  // aruco back end.
  ArucoRefinement arucoRefinement = ArucoRefinement::kContour;  // passes the real photographs

  // Region tracking (video): markers found in the last frame are looked for again only in a
  // box around where they were (moved on by their last motion), at full resolution
  // (decimate 1); the whole frame is searched (at `decimate`) only when an id in `ids` (or,
  // with no ids, any marker) is missing, at most every `searchEvery` frames, and what that
  // search finds is refined at full resolution in its box. Off: every frame is searched whole.
  bool regions = true;
  int searchEvery = 2;
  // Rigid sets of ids (a planet board, a tool cube): one of them counts as missing only when
  // none of its ids is found; while some are, the rest are searched for every setSearchEvery
  // frames (markers of a set that never face the camera together would otherwise keep the
  // whole-frame search running every searchEvery frames).
  std::vector<std::vector<int>> sets;
  int setSearchEvery = 8;
  // While every missing set is expected somewhere (Detector::expect: a covered board whose
  // pose the plane it lies on carries), its markers are looked for in the expected boxes every
  // frame and the whole frame only every expectedSearchEvery frames: a marker showing again
  // where it is expected is found in that frame, one showing elsewhere (a wrong prediction)
  // within expectedSearchEvery frames. 0 (the default): expectations are ignored (the whole
  // frame every searchEvery frames). Off because on board-covered-move 8 measured slower and
  // less accurate than without (docs/TRACKING.md, "Expected markers").
  int expectedSearchEvery = 0;
  // While a missing set is expected (Detector::expect, whatever expectedSearchEvery says) and
  // none is partly seen, the whole-frame search is made at this coarser decimation, and at
  // `decimate` every expectedFullSearchEvery frames: a board's markers at arm's length show at
  // 1/3 (the textured table around the hands is what a whole-frame search pays for). A coarse
  // search that returns any marker only says so: that frame is searched again at `decimate` and
  // its markers are taken (what is found is what the full search finds; markers the coarse one
  // misses, within expectedFullSearchEvery frames). 0: off (every search at `decimate`).
  double expectedSearchDecimate = 3.0;
  int expectedFullSearchEvery = 8;
  double regionMargin = 0.3;  // box margin, as a fraction of the marker's size in the image
  // A box that holds at least coarseRegionMarkers markers, each at least coarseRegionPx
  // pixels across, is searched at `decimate` (the quads found on the smaller image, their edges
  // still refined on the full one): a board's nine markers then cost about a third of a
  // full-resolution search, and the pose from 36 corners hardly notices (docs/TRACKING.md).
  // Fewer markers (a single marker, the tool cube's faces) keep the full resolution their
  // poses need. coarseRegionPx 0: always full resolution.
  double coarseRegionPx = 20;
  int coarseRegionMarkers = 4;
  // A rigid set of which one marker alone is found (a tool cube showing one face) gets that
  // marker's corners refined by aligning its canonical image with the frame (corner_refine.hpp):
  // a lone face seen nearly head-on turns by degrees for a tenth of a pixel at its corners,
  // where several faces hold each other's tilt. Markers outside the sets are untouched.
  bool refineLoneSetMarkers = true;
  // ... when it looks turned out of the image by at most this (from its quad): further turned,
  // the edge fit's corners hold the tilt as well and the alignment costs about 0.45 ms.
  double refineLoneMaxTiltDeg = 25.0;

  // Throws core::InputError naming the bad field.
  void validate() const;
};

class Detector {
 public:
  virtual ~Detector() = default;
  // "apriltag tag36h11 d2" etc. (benchmarks and logs)
  virtual std::string name() const = 0;
  virtual Backend backend() const = 0;
  // Markers in an 8-bit grey image (a BGR image is converted), sorted by id, then by TL corner.
  virtual std::vector<Detection> detect(const cv::Mat& image) = 0;
  // Where markers that were not found are expected in the next detect()'s image (a covered
  // board's markers placed by a pose carried without them), for that call only. The region
  // tracker searches there as around a marker seen last frame (DetectorConfig::
  // expectedSearchEvery); a detection's family, when set, picks the detector of that family.
  // Others ignore it.
  virtual void expect(const std::vector<Detection>& markers) { (void)markers; }
};

// The back end named in config (kAuto: AprilTag when the family is one of its own). Throws
// core::InputError for a family the back end cannot read or a bad setting.
std::unique_ptr<Detector> makeDetector(const DetectorConfig& config);

// Several families in one frame (a board of one family beside a tool of another): one
// detector per config (each config one family, with that family's ids and sets; two configs of
// one family are refused), run on one grey image made once. Detections come out in the order of
// the configs, then as each detector sorts them, each tagged with its family. One config: that
// config's detector. Throws core::InputError as makeDetector does, or for no config.
std::unique_ptr<Detector> makeDetector(const std::vector<DetectorConfig>& families);

// The region-tracking wrapper (what makeDetector returns when config.regions is set).
std::unique_ptr<Detector> makeRegionDetector(const DetectorConfig& config);

// Internal helpers, exposed for tests.
std::unique_ptr<Detector> makeArucoDetector(const DetectorConfig& config);
std::unique_ptr<Detector> makeAprilTagDetector(const DetectorConfig& config);
// Grey view of an image (no copy when it already is CV_8UC1); InputError for other types.
cv::Mat toGrey(const cv::Mat& image);
// Keeps the configured ids, tags each detection with the config's family, and sorts.
void finishDetections(const DetectorConfig& config, std::vector<Detection>& detections);

}  // namespace ps::tracking
