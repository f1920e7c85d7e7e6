// Marker detection: real photographs (OpenCV's own expected corners), corner conventions of
// both back ends on rendered markers with exactly known corners, family names.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/build_paths.hpp"
#include "core/input_error.hpp"
#include "tracking/body_pose.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/marker_layout.hpp"
#include "tracking/synth.hpp"
#include "tracking/textured_quad.hpp"

using namespace ps;
using tracking::Backend;

namespace {

const std::filesystem::path kRealMarkers = ps::app::sharedDir() / "data/real-markers";

// A marker drawn on a grey background with its edge corners (TL, TR, BR, BL of the canonical
// image) at exactly `corners` (pixels, OpenCV convention).
void drawMarker(cv::Mat& image, const std::string& family, int id,
                const std::array<cv::Point2d, 4>& corners) {
  const auto info = tracking::familyInfo(family);
  // On a paper card with a margin of three cells (aruco's own pipeline takes a one-cell white
  // ring on a grey background for the marker's edge).
  cv::Mat cells;
  cv::copyMakeBorder(tracking::markerCells(family, id), cells, 2, 2, 2, 2, cv::BORDER_CONSTANT,
                     cv::Scalar(255));
  const double a = info.edgeOffset + 2, b = info.edgeOffset + 2 + info.edgeCells;
  const std::vector<cv::Point2f> src = {
      {float(a), float(a)}, {float(b), float(a)}, {float(b), float(b)}, {float(a), float(b)}};
  std::vector<cv::Point2f> dst;
  for (const auto& c : corners) dst.emplace_back(float(c.x), float(c.y));
  const cv::Matx33d H = cv::getPerspectiveTransform(src, dst);
  tracking::drawTexturedQuad(image, cells, H, 8);
}

cv::Mat renderMarker(const std::string& family, int id, const std::array<cv::Point2d, 4>& corners,
                     cv::Size size = {320, 240}) {
  cv::Mat image(size, CV_8U, cv::Scalar(128));
  drawMarker(image, family, id, corners);
  return image;
}

double maxCornerError(const tracking::Detection& d, const std::array<cv::Point2d, 4>& truth) {
  double e = 0;
  for (int k = 0; k < 4; ++k)
    e = std::max(e, cv::norm(d.corners[std::size_t(k)] - truth[std::size_t(k)]));
  return e;
}

// The first frame of the board-covered-move scene (the hand off the board), in grey, and a
// frame of the same size with nothing in it (the board covered).
struct CoveredBoardScene {
  std::filesystem::path root = ps::app::sourceDir();
  tracking::MarkerLayout board = tracking::loadMarkerLayout(tracking::defaultBoardPath(root));
  tracking::SynthScript script = tracking::builtinScene("board-covered-move", root);
  tracking::FrameTruth truth;
  cv::Mat shown, covered;
  CoveredBoardScene() {
    tracking::SynthRenderer renderer(script);
    truth = renderer.truth(0);
    shown = renderer.render(0);
    if (shown.channels() == 3) cv::cvtColor(shown, shown, cv::COLOR_BGR2GRAY);
    covered = cv::Mat(shown.size(), CV_8U, cv::Scalar(128));
  }
};

}  // namespace

TEST(TrackingDetect, RealPhotographsMatchOpenCVsExpectedCorners) {
  if (!std::filesystem::exists(kRealMarkers / "singlemarkersoriginal.json"))
    GTEST_SKIP() << "no real marker photographs at " << kRealMarkers
                 << " (they live in the shared data folder; PS_SHARED_DIR names it)";
  for (const char* name : {"singlemarkersoriginal", "choriginal"}) {
    std::ifstream f(kRealMarkers / (std::string(name) + ".json"));
    const auto expected = nlohmann::json::parse(f);
    const cv::Mat image =
        cv::imread((kRealMarkers / expected["image"].get<std::string>()).string());
    ASSERT_FALSE(image.empty()) << name;
    tracking::DetectorConfig config;  // what `planetsculpt detect --family F` uses
    config.family = expected["dictionary"].get<std::string>();
    const auto found = tracking::makeDetector(config)->detect(image);
    const double tol = expected["tolerance_px"].get<double>();
    EXPECT_EQ(found.size(), expected["markers"].size()) << name;
    for (const auto& [id, xy] : expected["markers"].items()) {
      const int wanted = std::stoi(id);  // clang 14 cannot capture a structured binding
      const auto it =
          std::find_if(found.begin(), found.end(), [&](const auto& d) { return d.id == wanted; });
      ASSERT_NE(it, found.end()) << name << ": marker " << id << " not found";
      for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(it->corners[std::size_t(k)].x, xy[std::size_t(2 * k)].get<double>(), tol)
            << name << " id " << id << " corner " << k;
        EXPECT_NEAR(it->corners[std::size_t(k)].y, xy[std::size_t(2 * k + 1)].get<double>(), tol)
            << name << " id " << id << " corner " << k;
      }
    }
  }
}

TEST(TrackingDetect, BothBackEndsReportTheCanonicalCornersInOpenCVPixels) {
  // A tilted, rotated tag36h11 marker with corners at fractional positions; TL of the official
  // tag image must come first whatever the back end.
  const std::array<cv::Point2d, 4> truth = {cv::Point2d(201.3, 61.7), cv::Point2d(230.9, 170.2),
                                            cv::Point2d(118.4, 190.6), cv::Point2d(95.2, 80.1)};
  const cv::Mat image = renderMarker("tag36h11", 7, truth);
  struct Case {
    Backend backend;
    tracking::ArucoRefinement refine;
    double decimate, tol;
  };
  for (const Case& c :
       {Case{Backend::kAprilTag, {}, 1.0, 0.1}, Case{Backend::kAprilTag, {}, 2.0, 0.1},
        Case{Backend::kAruco, tracking::ArucoRefinement::kAprilTag, 1.0, 0.25},
        Case{Backend::kAruco, tracking::ArucoRefinement::kContour, 1.0, 1.0},
        Case{Backend::kAruco, tracking::ArucoRefinement::kNone, 1.0, 1.0}}) {
    tracking::DetectorConfig config;
    config.backend = c.backend;
    config.arucoRefinement = c.refine;
    config.decimate = c.decimate;
    auto det = tracking::makeDetector(config);
    const auto found = det->detect(image);
    ASSERT_EQ(found.size(), 1u) << det->name();
    EXPECT_EQ(found[0].id, 7) << det->name();
    EXPECT_LT(maxCornerError(found[0], truth), c.tol) << det->name();
  }
}

// Region tracking over a short noisy video: a near marker (about 180 px) and a far one (about
// 36 px), both moving, a cut at frame 6 where they jump (a whole-frame search), bright and dim
// (black and white 50 grey levels apart). With the default minimum contrast (20) and with the
// library's own (5), every frame must give both ids with the drawn corners.
TEST(TrackingDetect, RegionTrackingFindsNoisyNearAndFarMarkersWithTheirCorners) {
  auto quad = [](cv::Point2d c, double half, double turn, double squash) {
    std::array<cv::Point2d, 4> q;
    const cv::Point2d u(std::cos(turn), std::sin(turn)), v(-u.y, u.x);
    const double s[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (std::size_t k = 0; k < 4; ++k)
      q[k] = c + half * (s[k][0] * squash * u + s[k][1] * v) + cv::Point2d(0.013 * double(k), 0);
    return q;
  };
  for (int minContrast : {tracking::DetectorConfig{}.minContrast, 5}) {
    for (double gain : {1.0, 0.2}) {
      tracking::DetectorConfig config;
      config.ids = {3, 7};
      config.minContrast = minContrast;
      auto det = tracking::makeDetector(config);
      cv::RNG rng(17);
      double worst = 0;
      for (int f = 0; f < 12; ++f) {
        const double jump = f < 6 ? 0.0 : 1.0;
        const auto nearCorners = quad({250.3 + 2.7 * f + 60 * jump, 230.6 - 1.9 * f},
                                      90.2 - 0.8 * f, 0.15 + 0.01 * f - 0.3 * jump, 0.8);
        const auto farCorners =
            quad({540.4 - 1.3 * f, 90.2 + 280 * jump + 0.9 * f}, 18.3, -0.4, 0.7);
        cv::Mat image(480, 640, CV_8U, cv::Scalar(128));
        drawMarker(image, "tag36h11", 3, nearCorners);
        drawMarker(image, "tag36h11", 7, farCorners);
        cv::GaussianBlur(image, image, {0, 0}, 0.6);
        cv::Mat noisy(image.size(), CV_32F);
        rng.fill(noisy, cv::RNG::NORMAL, 0.0, 1.5);
        cv::Mat level;
        image.convertTo(level, CV_32F, gain, 128 * (1 - gain));
        cv::Mat(level + noisy).convertTo(image, CV_8U);
        const auto found = det->detect(image);
        const std::string what = "min contrast " + std::to_string(minContrast) + " gain " +
                                 std::to_string(gain) + " frame " + std::to_string(f);
        ASSERT_EQ(found.size(), 2u) << what;
        EXPECT_EQ(found[0].id, 3) << what;
        EXPECT_EQ(found[1].id, 7) << what;
        worst = std::max(
            {worst, maxCornerError(found[0], nearCorners), maxCornerError(found[1], farCorners)});
      }
      EXPECT_LT(worst, 0.3) << "min contrast " << minContrast << " gain " << gain;
      RecordProperty("worst_corner_px_contrast" + std::to_string(minContrast) + "_gain" +
                         std::to_string(int(gain * 10)),
                     std::to_string(worst));
    }
  }
}

// Region boxes holding many large markers of one rigid set (the board) are searched at the
// frame's decimation, the rest at full resolution. On the board demo's first 60 frames (the
// tool sweeping over the board) the board's pose from the coarse search puts the planet's
// centre as close to the truth as the full-resolution search's (measured, one frame's pose, no
// filter: 0.35 / 0.84 mm median / p95 against 0.36 / 0.64 mm; the corners 0.12 / 1.50 px
// against 0.10 / 0.96 px, which 36 corners mostly absorb); a single-marker scene, with
// no such set, is detected bit for bit as before.
TEST(TrackingDetect, CoarseRegionSearchOnlyWhereABoxHoldsManyMarkers) {
  const auto root = ps::app::sourceDir();
  const auto board = tracking::loadMarkerLayout(tracking::defaultBoardPath(root));
  const auto cube = tracking::loadMarkerLayout(tracking::defaultToolLayoutPath(root));
  auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[std::size_t(q * double(v.size() - 1))];
  };
  for (const std::string scene : {"board-demo", "short"}) {
    const auto script = tracking::builtinScene(scene, root);
    tracking::SynthRenderer renderer(script);
    tracking::DetectorConfig coarse;
    if (scene == "short") {
      coarse.ids = {0, 1};
    } else {
      coarse.ids = board.ids();
      for (int id : cube.ids()) coarse.ids.push_back(id);
      coarse.sets = {board.ids(), cube.ids()};
    }
    ASSERT_GT(coarse.coarseRegionPx, 0);
    tracking::DetectorConfig fine = coarse;
    fine.coarseRegionPx = 0;
    auto a = tracking::makeDetector(coarse), b = tracking::makeDetector(fine);
    std::vector<double> coarseMm, fineMm;
    bool identical = true;
    for (int f = 0; f < std::min(renderer.frames(), 60); ++f) {
      const cv::Mat image = renderer.render(f);
      const auto x = a->detect(image), y = b->detect(image);
      identical &= x.size() == y.size();
      for (std::size_t i = 0; identical && i < x.size(); ++i)
        identical &= x[i].id == y[i].id && maxCornerError(x[i], y[i].corners) == 0;
      if (scene == "short") continue;
      const auto truth = renderer.truth(f);
      auto centreErrorMm = [&](const std::vector<tracking::Detection>& found) {
        const auto r = tracking::solveBodyPose(board, found, script.camera, nullptr, 4.0);
        if (!r.valid) return 1e9;
        return 1e3 * (r.pose.apply(*board.planetCentre) - truth.planetCentreCamera).norm();
      };
      coarseMm.push_back(centreErrorMm(x));
      fineMm.push_back(centreErrorMm(y));
    }
    if (scene == "short") {
      EXPECT_TRUE(identical) << "single markers were searched coarsely";
      continue;
    }
    EXPECT_FALSE(identical) << "the board's box was never searched coarsely";
    ASSERT_EQ(coarseMm.size(), 60u);
    const double coarseMedian = quantile(coarseMm, 0.5), fineMedian = quantile(fineMm, 0.5);
    const double coarseP95 = quantile(coarseMm, 0.95), fineP95 = quantile(fineMm, 0.95);
    EXPECT_LT(coarseMedian, fineMedian + 0.15);
    EXPECT_LT(coarseP95, std::max(1.25 * fineP95, fineP95 + 0.3));
    EXPECT_LT(coarseP95, 3.0);  // the target for the planet's centre
    RecordProperty("centre_mm_coarse",
                   std::to_string(coarseMedian) + " / " + std::to_string(coarseP95));
    RecordProperty("centre_mm_full", std::to_string(fineMedian) + " / " + std::to_string(fineP95));
  }
}

// A covered board's markers expected where a carried pose puts them (Detector::expect): a board
// showing again there is found in that frame, whatever the frame's phase in the whole-frame
// search's cycle; one showing elsewhere (the expectation wrong) is found by the whole-frame
// search within expectedSearchEvery frames, however long the board was gone before.
TEST(TrackingDetect, ExpectedBoardIsFoundAtOnceThereAndWithinTheSearchCycleElsewhere) {
  const CoveredBoardScene scene;
  ASSERT_GE(scene.truth.boardHalfVisible, 6);
  const auto& board = scene.board;
  const cv::Mat& shown = scene.shown;
  const cv::Mat& covered = scene.covered;
  const auto truePx = tracking::projectLayout(board, scene.truth.planet, scene.script.camera);
  // Right: the board's own corners. Wrong: the board shrunk into the image's top-left corner,
  // clear of where it is.
  double x0 = 1e9, y0 = 1e9;
  cv::Rect2d trueExtent(truePx[0][0], truePx[0][0]);
  for (const auto& q : truePx)
    for (const auto& c : q) {
      x0 = std::min(x0, c.x), y0 = std::min(y0, c.y);
      trueExtent |= cv::Rect2d(c, c + cv::Point2d(1, 1));
    }
  std::vector<tracking::Detection> right, wrong;
  cv::Rect2d wrongExtent(8, 8, 1, 1);
  for (std::size_t i = 0; i < board.markers.size(); ++i) {
    tracking::Detection d;
    d.id = board.markers[i].id;
    d.corners = truePx[i];
    right.push_back(d);
    for (auto& c : d.corners) {
      c = cv::Point2d(8, 8) + 0.4 * (c - cv::Point2d(x0, y0));
      wrongExtent |= cv::Rect2d(c, c + cv::Point2d(1, 1));
    }
    wrong.push_back(d);
  }
  // Apart by more than the search boxes' margins.
  const double gap = std::max(trueExtent.x - wrongExtent.br().x, trueExtent.y - wrongExtent.br().y);
  ASSERT_GT(gap, 40.0);
  tracking::DetectorConfig config;
  config.ids = board.ids();
  config.sets = {board.ids()};
  config.expectedSearchEvery = 8;  // off by default (detector.hpp)
  auto boardFound = [&](const std::vector<tracking::Detection>& found) {
    return std::count_if(found.begin(), found.end(),
                         [&](const auto& d) { return board.find(d.id) != nullptr; }) >= 4;
  };
  int slowest = 0;
  for (int coveredFrames = 1; coveredFrames <= 2 * config.expectedSearchEvery; ++coveredFrames) {
    for (const auto* expected : {&right, &wrong}) {
      auto det = tracking::makeDetector(config);
      ASSERT_TRUE(boardFound(det->detect(shown)));
      for (int f = 0; f < coveredFrames; ++f) {
        det->expect(*expected);
        ASSERT_TRUE(det->detect(covered).empty());
      }
      int waited = 0;
      for (;; ++waited) {
        det->expect(*expected);
        if (boardFound(det->detect(shown)) || waited > 3 * config.expectedSearchEvery) break;
      }
      if (expected == &right) {
        EXPECT_EQ(waited, 0) << "shown where expected after " << coveredFrames << " frames";
      } else {
        EXPECT_LT(waited, config.expectedSearchEvery)
            << "shown elsewhere after " << coveredFrames << " covered frames";
        slowest = std::max(slowest, waited);
      }
    }
  }
  // The whole frame was searched less often than every searchEvery frames: the expectation
  // took effect (else this test checks nothing of it).
  EXPECT_GE(slowest, config.searchEvery);
  RecordProperty("frames_to_find_elsewhere_max", slowest);
}

// A covered board carried by a pose (Detector::expect, whatever expectedSearchEvery says) is
// looked for by a whole-frame search at expectedSearchDecimate every searchEvery frames, and at
// `decimate` every expectedFullSearchEvery frames. Its markers at arm's length show to the coarse
// search: found within searchEvery frames of showing again, as without the expectation. A board
// too small for the coarse search (a marker of it found at decimate 2, none at 3) is still found
// within expectedFullSearchEvery frames, whatever the cycle's phase; without an expectation it is
// found within searchEvery frames, so the slower finds are the coarse search's doing.
TEST(TrackingDetect, CarriedBoardIsSearchedCoarselyAndWithinTheFullSearchCycle) {
  const CoveredBoardScene scene;
  ASSERT_GE(scene.truth.boardHalfVisible, 6);
  const auto& board = scene.board;
  const cv::Mat& shown = scene.shown;
  const cv::Mat& covered = scene.covered;
  tracking::DetectorConfig config;
  config.ids = board.ids();
  config.sets = {board.ids()};
  ASSERT_EQ(config.expectedSearchEvery, 0);  // the default: no expected boxes
  ASSERT_GT(config.expectedSearchDecimate, config.decimate);
  auto boardCount = [&](const std::vector<tracking::Detection>& found) {
    return std::count_if(found.begin(), found.end(),
                         [&](const auto& d) { return board.find(d.id) != nullptr; });
  };
  // The frame shrunk onto a grey canvas of its size, until the coarse search alone misses it.
  auto wholeFrame = [&](double decimate) {
    tracking::DetectorConfig c = config;
    c.regions = false;
    c.decimate = decimate;
    return tracking::makeDetector(c);
  };
  cv::Mat small;
  for (double scale = 0.9; scale > 0.15 && small.empty(); scale -= 0.05) {
    cv::Mat canvas(shown.size(), CV_8U, cv::Scalar(128)), shrunk;
    cv::resize(shown, shrunk, cv::Size(), scale, scale, cv::INTER_AREA);
    shrunk.copyTo(canvas(cv::Rect(0, 0, shrunk.cols, shrunk.rows)));
    const auto fine = boardCount(wholeFrame(config.decimate)->detect(canvas));
    const auto coarse = boardCount(wholeFrame(config.expectedSearchDecimate)->detect(canvas));
    if (fine >= 1 && coarse == 0) small = canvas;
  }
  ASSERT_FALSE(small.empty()) << "no size at which only the finer search finds the board";
  std::vector<tracking::Detection> expected;
  for (int id : board.ids()) {
    tracking::Detection d;
    d.id = id;
    expected.push_back(d);  // where does not matter here: expectedSearchEvery is 0
  }
  // Frames until the board is found again after `coveredFrames` covered ones.
  auto framesToFind = [&](const cv::Mat& image, int coveredFrames, bool carried) {
    auto det = tracking::makeDetector(config);
    EXPECT_GE(boardCount(det->detect(image)), 1);
    for (int f = 0; f < coveredFrames; ++f) {
      if (carried) det->expect(expected);
      EXPECT_TRUE(det->detect(covered).empty());
    }
    int waited = 0;
    for (; waited <= 3 * config.expectedFullSearchEvery; ++waited) {
      if (carried) det->expect(expected);
      if (boardCount(det->detect(image)) >= 1) break;
    }
    return waited;
  };
  int slowestSmall = 0;
  for (int coveredFrames = 1; coveredFrames <= 2 * config.expectedFullSearchEvery;
       ++coveredFrames) {
    EXPECT_LT(framesToFind(shown, coveredFrames, true), config.searchEvery)
        << "carried, after " << coveredFrames << " covered frames";
    const int smallCarried = framesToFind(small, coveredFrames, true);
    EXPECT_LT(smallCarried, config.expectedFullSearchEvery)
        << "small, carried, after " << coveredFrames << " covered frames";
    slowestSmall = std::max(slowestSmall, smallCarried);
    EXPECT_LT(framesToFind(small, coveredFrames, false), config.searchEvery)
        << "small, not carried, after " << coveredFrames << " covered frames";
  }
  EXPECT_GE(slowestSmall, config.searchEvery) << "the coarse search never took the full one's turn";
  RecordProperty("small_board_frames_to_find_max", slowestSmall);
}

TEST(TrackingDetect, ArucoDictionariesAndIdFilter) {
  const std::array<cv::Point2d, 4> truth = {cv::Point2d(60.5, 50.25), cv::Point2d(170.0, 40.0),
                                            cv::Point2d(180.0, 160.0), cv::Point2d(55.0, 150.0)};
  const cv::Mat image = renderMarker("DICT_4X4_50", 13, truth);
  tracking::DetectorConfig config;
  config.family = "DICT_4X4_50";
  auto found = tracking::makeDetector(config)->detect(image);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].id, 13);
  EXPECT_LT(maxCornerError(found[0], truth), 1.0);
  config.ids = {1, 2};
  EXPECT_TRUE(tracking::makeDetector(config)->detect(image).empty());
}

TEST(TrackingDetect, FamiliesAndBadConfigurations) {
  EXPECT_EQ(tracking::familyInfo("tag36h11").edgeCells, 8);
  EXPECT_EQ(tracking::familyInfo("tag36h11").totalCells, 10);
  EXPECT_EQ(tracking::familyInfo("tag36h11").markerCount, 587);
  EXPECT_EQ(tracking::familyInfo("DICT_6X6_250").edgeCells, 8);
  EXPECT_EQ(tracking::familyInfo("DICT_6X6_250").markerCount, 250);
  // OpenCV's DICT_APRILTAG_36h11 marker is the official one turned by 180 degrees.
  {
    cv::Mat official = tracking::markerCells("tag36h11", 5), opencv;
    cv::rotate(tracking::markerCells("DICT_APRILTAG_36h11", 5), opencv, cv::ROTATE_180);
    EXPECT_EQ(cv::norm(official, opencv, cv::NORM_INF), 0.0);
  }
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const core::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(
      message([] { tracking::familyInfo("tag99h1"); }).find("unknown marker family 'tag99h1'"),
      std::string::npos);
  EXPECT_NE(message([] { tracking::markerCells("tag36h11", 587); }).find("587"), std::string::npos);
  tracking::DetectorConfig c;
  c.family = "DICT_6X6_250";
  c.backend = Backend::kAprilTag;
  EXPECT_NE(message([&] { tracking::makeDetector(c); }).find("cannot read DICT_6X6_250"),
            std::string::npos);
  c = {};
  c.family = "tagStandard41h12";
  c.backend = Backend::kAruco;
  EXPECT_NE(message([&] { tracking::makeDetector(c); }).find("no dictionary"), std::string::npos);
  c = {};
  c.decimate = 0.5;
  EXPECT_NE(message([&] { tracking::makeDetector(c); }).find("decimate"), std::string::npos);
  c = {};
  c.minContrast = 300;
  EXPECT_NE(message([&] { tracking::makeDetector(c); }).find("min contrast"), std::string::npos);
  EXPECT_NE(message([] { tracking::toGrey(cv::Mat()); }).find("empty image"), std::string::npos);
}
