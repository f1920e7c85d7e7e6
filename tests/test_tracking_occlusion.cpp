// Tracking through occlusion: the camera-stillness judge on images with known motion, and the
// planet board replayed through synthetic scenes with hands over it (ground truth from synth).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

#include "app/build_paths.hpp"
#include "core/input_error.hpp"
#include "replay/replay.hpp"
#include "stress_util.hpp"
#include "test_terrains.hpp"

#include "tracking/camera_motion.hpp"
#include "tracking/detector.hpp"
#include "tracking/plane_tracker.hpp"
#include "tracking/synth.hpp"
#include "tracking/tool_shape.hpp"
#include "tracking/tracker.hpp"

using namespace ps;

namespace {

// A table-like texture: blobs and lines at random, smoothed.
cv::Mat texture(cv::Size size, unsigned seed) {
  cv::Mat img(size, CV_8U, cv::Scalar(120));
  cv::RNG rng(seed);
  for (int i = 0; i < 300; ++i) {
    const cv::Point c(rng.uniform(0, size.width), rng.uniform(0, size.height));
    cv::circle(img, c, rng.uniform(2, 14), cv::Scalar(rng.uniform(0, 255)), cv::FILLED,
               cv::LINE_AA);
  }
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.0);
  return img;
}

cv::Mat shifted(const cv::Mat& img, double dx, double dy) {
  cv::Mat out;
  const cv::Matx23d m(1, 0, dx, 0, 1, dy);
  cv::warpAffine(img, out, m, img.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

}  // namespace

TEST(TrackingOcclusion, CameraMotionJudgeTellsStillFromMoved) {
  const cv::Mat ref = texture({640, 480}, 1);
  tracking::CameraMotionJudge judge;
  EXPECT_FALSE(judge.judge(ref).judged) << "no reference yet";
  judge.setReference(ref, {});
  for (double s : {0.0, 0.4, 0.9}) {
    const auto m = judge.judge(shifted(ref, s, -s * 0.5));
    ASSERT_TRUE(m.judged);
    EXPECT_TRUE(m.still) << "shift " << s << " px: median " << m.medianShiftPx;
    EXPECT_NEAR(m.medianShiftPx, std::hypot(s, 0.5 * s), 0.15);
  }
  for (double s : {2.5, 6.0, 20.0}) {
    const auto m = judge.judge(shifted(ref, s, 0.3 * s));
    EXPECT_FALSE(m.still) << "shift " << s << " px: median " << m.medianShiftPx;
  }
}

// A hand moving over a third of the image does not make a still camera look moved; the marker
// quads given as exclusions are not used at all.
TEST(TrackingOcclusion, CameraMotionJudgeIgnoresAMovingHandAndTheMarkers) {
  const cv::Mat ref = texture({640, 480}, 2);
  tracking::CameraMotionJudge judge;
  const std::array<cv::Point2d, 4> quad = {cv::Point2d(300, 200), cv::Point2d(380, 200),
                                           cv::Point2d(380, 280), cv::Point2d(300, 280)};
  judge.setReference(ref, {quad});
  for (int step = 0; step < 10; ++step) {
    cv::Mat now = ref.clone();
    // The "hand": a textured disc that moves 12 px a frame over the image's left third.
    cv::Mat hand = texture({640, 480}, 100 + unsigned(step));
    cv::Mat mask(now.size(), CV_8U, cv::Scalar(0));
    cv::circle(mask, {60 + 12 * step, 240}, 120, cv::Scalar(255), cv::FILLED);
    hand.copyTo(now, mask);
    // Whatever happens inside the excluded quad (a marker changing) does not count.
    cv::rectangle(now, {300, 200}, {380, 280}, cv::Scalar(step * 25), cv::FILLED);
    const auto m = judge.judge(now);
    EXPECT_TRUE(m.still) << "step " << step << ": median " << m.medianShiftPx << ", tracked "
                         << m.tracked << " of " << m.features;
  }
  // The same hand with the camera panned 4 px: moved.
  const auto m = judge.judge(shifted(ref, 4, 0));
  EXPECT_FALSE(m.still);
}

// A slow pan adds up against the reference: 0.3 px a frame is under any per-frame threshold,
// but after 10 frames the camera has moved 3 px and is judged so.
TEST(TrackingOcclusion, CameraMotionJudgeAccumulatesASlowPan) {
  const cv::Mat ref = texture({640, 480}, 3);
  tracking::CameraMotionJudge judge;
  judge.setReference(ref, {});
  int firstMoved = -1;
  for (int f = 1; f <= 20 && firstMoved < 0; ++f)
    if (!judge.judge(shifted(ref, 0.3 * f, 0)).still) firstMoved = f;
  EXPECT_GE(firstMoved, 4);  // 1.2 px: still within the 1.5 px bound
  EXPECT_LE(firstMoved, 7);  // 2.1 px: moved
}

// The judge tracks its 40 strongest corners first and stops there when the camera is clearly
// still (half of them back, median <= 0.5 px): the same verdicts as tracking all 150, frame by
// frame, through a still stretch, a slow pan and a hand over a third of the image.
TEST(TrackingOcclusion, CameraMotionJudgeDecidesClearlyStillFramesOnItsFirstCorners) {
  const cv::Mat ref = texture({640, 480}, 4);
  tracking::CameraMotionConfig all;
  all.firstBatch = 0;
  tracking::CameraMotionJudge cheap, full(all);
  cheap.setReference(ref, {});
  full.setReference(ref, {});
  int early = 0, frames = 0;
  for (int f = 0; f < 24; ++f) {
    // Still for 6 frames, then panning 0.3 px a frame; a hand over the left third throughout.
    cv::Mat now = shifted(ref, f < 6 ? 0.0 : 0.3 * (f - 5), 0);
    cv::Mat hand = texture({640, 480}, 200 + unsigned(f));
    cv::Mat mask(now.size(), CV_8U, cv::Scalar(0));
    cv::circle(mask, {60 + 10 * f, 240}, 110, cv::Scalar(255), cv::FILLED);
    hand.copyTo(now, mask);
    const auto a = cheap.judge(now), b = full.judge(now);
    ASSERT_TRUE(a.judged && b.judged);
    EXPECT_EQ(a.still, b.still) << "frame " << f << ": " << a.medianShiftPx << " against "
                                << b.medianShiftPx << " px";
    EXPECT_FALSE(b.early);
    if (a.early) {
      ++early;
      EXPECT_LE(b.medianShiftPx, 0.75) << "frame " << f;
      EXPECT_LE(a.tracked, 40);
    }
    ++frames;
  }
  EXPECT_GE(early, 6) << "the still frames end on the first corners";
  EXPECT_LT(early, frames) << "a pan past 0.5 px tracks them all";
}

namespace {

struct OcclusionRun {
  int halfVisible = 0, halfVisibleWithPose = 0;
  int hiddenStill = 0, hiddenStillWithPose = 0;
  int hiddenMoved = 0, falseHolds = 0;  // held with the planet centre > 5 mm off
  // Frames without the board in which the camera was judged, with the planet held or lost after
  // the frame before (once lost, there is nothing for the camera's stillness to keep).
  int judgedWhileHeld = 0, judgedAfterLoss = 0;
  std::vector<double> centreErr;  // frames with a board marker at least half visible
  std::vector<double> movedErr;   // hidden, the camera moved, with a pose
  int carried = 0;                // poses carried by the plane around the board
  // Held (not carried) with the planet's true centre more than 3 mm (in the image's frame) from
  // where it was when the board was last measured: a pose known to be stale.
  int stale = 0;
  int drawnOff10 = 0;  // frames with a pose more than 10 mm off
};

// Replays a built-in board scene through the frame stepper (the pipeline `replay` and `live`
// run) and compares the planet's pose with the ground truth, frame by frame. Every `step`th frame
// only (the video then runs at 30/step fps; the holds count in seconds): rendering is what costs
// here, and `bench track` runs the scenes whole.
OcclusionRun replayBoardScene(const std::string& name, int step, const std::string& table = "") {
  auto script = tracking::builtinScene(name, ps::app::sourceDir());
  if (!table.empty()) script.table = table;
  const tracking::SynthRenderer renderer(script);
  terrain::Terrain planet = testkit::bumpyTerrain(7);
  replay::ReplayOptions o;
  o.scene.useBoard(script.board);
  o.scene.useToolLayout(script.toolLayout);
  o.scene.planetRadius = script.planetRadius;
  replay::FrameStepper stepper(script.camera, planet, o);
  OcclusionRun r;
  tracking::Pose lastSeenCamera;
  Eigen::Vector3d lastSeenCentre = Eigen::Vector3d::Zero();
  bool seen = false, hadPose = false;
  for (int f = 0; f < renderer.frames(); f += step) {
    const auto truth = renderer.truth(f);
    const auto result = stepper.step(renderer.render(f), f, truth.time);
    const auto& sf = result.scene;
    if (result.logLine.find("camera_shift_px") != std::string::npos)
      ++(hadPose ? r.judgedWhileHeld : r.judgedAfterLoss);
    hadPose = sf.planet.usable();
    const double err = sf.planetCentreValid
                           ? (sf.planetCentreCamera - truth.planetCentreCamera).norm()
                           : std::numeric_limits<double>::infinity();
    if (truth.boardHalfVisible > 0) {
      ++r.halfVisible;
      r.halfVisibleWithPose += sf.planetCentreValid ? 1 : 0;
      if (!sf.planetCentreValid && std::getenv("PS_DEBUG_OCCLUSION"))
        std::fprintf(stderr, "frame %d: %d half visible, state %s\n", f, truth.boardHalfVisible,
                     tracking::toString(sf.planet.state).c_str());
      if (sf.planetCentreValid) r.centreErr.push_back(err);
    } else if (seen) {
      const bool cameraAsWhenSeen =
          tracking::rotationAngle(lastSeenCamera.R, truth.camera.R) < 1e-6 &&
          (lastSeenCamera.t - truth.camera.t).norm() < 1e-6;
      if (cameraAsWhenSeen) {
        ++r.hiddenStill;
        r.hiddenStillWithPose += sf.planetCentreValid ? 1 : 0;
      } else {
        ++r.hiddenMoved;
        r.falseHolds += sf.planetCentreValid && err > 5e-3 ? 1 : 0;
        if (sf.planetCentreValid) r.movedErr.push_back(err);
      }
      if (sf.planet.usable() && !sf.planet.carried &&
          (truth.planetCentreCamera - lastSeenCentre).norm() > 3e-3) {
        ++r.stale;
        if (std::getenv("PS_DEBUG_OCCLUSION"))
          std::fprintf(stderr, "frame %d: held %.1f mm off\n", f, 1e3 * err);
      }
    }
    r.carried += sf.planet.carried ? 1 : 0;
    r.drawnOff10 += sf.planetCentreValid && err > 0.01 ? 1 : 0;
    if (sf.planet.measured) {
      lastSeenCamera = truth.camera;
      lastSeenCentre = truth.planetCentreCamera;
      seen = true;
    }
  }
  return r;
}

// Under the sanitizers, every 4th frame (the renderer is 5x slower there).
constexpr int kStep = testkit::underAsan() ? 4 : 2;
// Frames with part of the board uncovered but no pose: only right after a loss (the camera moved
// while the board was hidden), while the markers coming out from under the hand are still partly
// covered (a tag is read whole or not at all). `bench track` measures the share over all the
// board scenes (target: a pose in >= 99 % of them).
constexpr int kReacquireFrames = 3;

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? std::numeric_limits<double>::infinity()
                   : v[std::size_t(q * double(v.size() - 1))];
}

}  // namespace

// The board fully hidden for 2 s with the camera still, then the camera moving while it is
// still hidden: held while still, lost within the short hold (0.25 s) once the camera moves.
TEST(TrackingOcclusion, BoardHiddenIsHeldWhileTheCameraStandsAndLostWhenItMoves) {
  const OcclusionRun r = replayBoardScene("board-hidden", kStep);
  ASSERT_GT(r.hiddenStill, 40 / kStep);
  ASSERT_GT(r.hiddenMoved, 20 / kStep);
  EXPECT_GE(r.hiddenStillWithPose, r.hiddenStill * 95 / 100)
      << r.hiddenStillWithPose << " of " << r.hiddenStill << " still, hidden frames with a pose";
  EXPECT_LE(r.falseHolds, 8 / kStep + 1)
      << "frames held more than 5 mm off after the camera moved (of " << r.hiddenMoved << ")";
  EXPECT_LE(r.halfVisible - r.halfVisibleWithPose, kReacquireFrames);
  EXPECT_LT(quantile(r.centreErr, 0.5), 1e-3);
  EXPECT_LT(quantile(r.centreErr, 0.95), 3e-3);
  EXPECT_GE(r.judgedWhileHeld, r.hiddenStill) << "every held frame judged";
  EXPECT_EQ(r.judgedAfterLoss, 0) << "nothing to keep once lost";
}

// A hand over half the board, then over all of it: the planet stays, where it is.
TEST(TrackingOcclusion, BoardUnderAHandKeepsThePlanet) {
  const OcclusionRun r = replayBoardScene("board-hand", kStep);
  ASSERT_GT(r.halfVisible, 100 / kStep);
  EXPECT_LE(r.halfVisible - r.halfVisibleWithPose, kReacquireFrames)
      << r.halfVisibleWithPose << " of " << r.halfVisible;
  EXPECT_GE(r.hiddenStillWithPose, r.hiddenStill * 95 / 100)
      << r.hiddenStillWithPose << " of " << r.hiddenStill;
  EXPECT_LT(quantile(r.centreErr, 0.5), 1e-3);
  EXPECT_LT(quantile(r.centreErr, 0.95), 3e-3);
}

// On a textured table, the board covered whole by a hand while the camera moves round it: the
// planet is carried by the table that shows around the hand, close to the truth, and no pose
// is held once the camera has moved from where it stood when the board was last seen.
TEST(TrackingOcclusion, ACoveredBoardIsCarriedByTheTableWhileTheCameraMoves) {
  const OcclusionRun r = replayBoardScene("board-covered-move", 1);
  ASSERT_GT(r.hiddenMoved, 100) << "the scene covers the board while the camera moves";
  EXPECT_GE(r.movedErr.size(), std::size_t(r.hiddenMoved) * 9 / 10)
      << r.movedErr.size() << " of " << r.hiddenMoved << " hidden, moved frames with a pose";
  EXPECT_GE(r.carried, r.hiddenMoved * 8 / 10);
  EXPECT_LE(quantile(r.movedErr, 0.5), 2e-3);
  EXPECT_LE(quantile(r.movedErr, 0.95), 5e-3);
  EXPECT_EQ(r.stale, 0) << "held poses after the camera moved";
  EXPECT_EQ(r.drawnOff10, 0);
  EXPECT_LE(r.halfVisible - r.halfVisibleWithPose, kReacquireFrames);
}

// The same recording on a featureless table: nothing carries the planet, and it is lost rather
// than drawn where it is not (nor held where it was).
TEST(TrackingOcclusion, ACoveredBoardOnAPlainTableIsLostNotDrawnWrong) {
  const OcclusionRun r = replayBoardScene("board-covered-move", 1, "plain");
  ASSERT_GT(r.hiddenMoved, 100);
  EXPECT_EQ(r.drawnOff10, 0);
  EXPECT_EQ(r.stale, 0);
  EXPECT_LE(r.movedErr.size(), std::size_t(r.hiddenMoved) / 10)
      << "frames with a pose though nothing could carry it";
  for (double e : r.movedErr) EXPECT_LE(e, 5e-3);
}

// The tool over a marker's outline, against the tool drawn: its triangles (tool_shape.hpp) filled
// into the image, and each pixel's distance to the marker's edges. Whenever a drawn tool pixel
// lies inside the band about an edge (a pixel's margin for the drawing), the tool covers the
// outline; whenever it is said to cover it, a drawn pixel lies within the band's corners (the
// band is a strip, square at its ends) and the cone's outline (an octagon about each ring).
TEST(TrackingOcclusion, ToolCoversMarkerOutlineAgreesWithTheToolDrawn) {
  const auto cam = tracking::CameraCalibration::pinhole(600, 600, 319.5, 239.5, {640, 480});
  const tracking::SceneConfig sc;  // a single tool marker on its card and stick
  const tracking::ToolShape shape = tracking::toolShape(sc);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  int covered = 0, clear = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double depth = 0.5 + 0.2 * u(rng);
    const tracking::Pose planet = tracking::Pose::fromRvecTvec(
        {M_PI + 0.6 * u(rng), 0.6 * u(rng), M_PI * u(rng)}, {0.05 * u(rng), 0.05 * u(rng), depth});
    const tracking::Pose tool = tracking::Pose::fromRvecTvec(
        {M_PI + 0.7 * u(rng), 0.7 * u(rng), M_PI * u(rng)},
        {planet.t.x() + 0.08 * u(rng), planet.t.y() + 0.08 * u(rng), depth - 0.1 + 0.05 * u(rng)});
    const auto quad = tracking::projectMarker(planet, 0.08, cam);
    const double band = trial % 2 ? 0.25 : 1.0;
    const bool says = tracking::toolCoversMarkerOutline(shape, tool, cam, quad, 8, band);
    // The drawn tool, and each pixel's distance to the outline.
    cv::Mat toolMask(cam.imageSize, CV_8U, cv::Scalar(0)),
        notEdge(cam.imageSize, CV_8U, cv::Scalar(255));
    const auto triangles = tracking::toolTriangles(shape, tool, 1.0, 48);
    for (std::size_t i = 0; i + 2 < triangles.size(); i += 3) {
      std::vector<cv::Point> tri;
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::Vector3d& x = triangles[i + k];
        tri.emplace_back(int(std::lround(cam.K(0, 0) * x.x() / x.z() + cam.K(0, 2))),
                         int(std::lround(cam.K(1, 1) * x.y() / x.z() + cam.K(1, 2))));
      }
      cv::fillConvexPoly(toolMask, tri, cv::Scalar(255));
    }
    for (int k = 0; k < 4; ++k)
      cv::line(
          notEdge, cv::Point(int(std::lround(quad[k].x)), int(std::lround(quad[k].y))),
          cv::Point(int(std::lround(quad[(k + 1) % 4].x)), int(std::lround(quad[(k + 1) % 4].y))),
          cv::Scalar(0));
    cv::Mat dist;
    cv::distanceTransform(notEdge, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    double nearest = std::numeric_limits<double>::infinity();
    for (int y = 0; y < dist.rows; ++y)
      for (int x = 0; x < dist.cols; ++x)
        if (toolMask.at<unsigned char>(y, x))
          nearest = std::min(nearest, double(dist.at<float>(y, x)));
    double perimeter = 0;
    for (int k = 0; k < 4; ++k) perimeter += cv::norm(quad[k] - quad[(k + 1) % 4]);
    const double bandPx = band * perimeter / 32;
    if (nearest <= bandPx - 1.5) {
      EXPECT_TRUE(says) << trial << ": drawn " << nearest << " px off";
    }
    if (says) {
      EXPECT_LE(nearest, bandPx * std::sqrt(2.0) + 2.5)
          << trial << ": said covered, drawn " << nearest << " px off";
    }
    ++(says ? covered : clear);
  }
  EXPECT_GE(covered, 50);
  EXPECT_GE(clear, 50);
}

namespace {

struct SweepRun {
  int drawnOff10 = 0;             // frames with a planet more than 10 mm off
  int visible = 0, measured = 0;  // frames with the planet marker in view and uncovered
  int covered = 0;                // detections not used: the tool covered their outline
};

// The single-marker sweep's shots 8 and 9 (frames 160-199), as `bench track` runs them (a cut
// restarts the trackers): the tool's stick and card come over the planet marker's corners.
SweepRun replaySweepShots(double coverBandCells) {
  const auto script = tracking::builtinScene("sweep", ps::app::sourceDir());
  const tracking::SynthRenderer renderer(script);
  tracking::SceneConfig sc;
  sc.planet.id = script.planetId;
  sc.planet.size = script.planetMarkerSize;
  sc.tool.id = script.toolId;
  sc.tool.size = script.toolMarkerSize;
  sc.planetRadius = script.planetRadius;
  sc.tipOffset = script.tipOffset;
  sc.toolCoverBandCells = coverBandCells;
  tracking::DetectorConfig dc;
  dc.ids = {sc.planet.id, sc.tool.id};
  const auto detector = tracking::makeDetector(dc);
  tracking::SceneTracker tracker(sc);
  SweepRun r;
  for (int f = 160; f < 200; ++f) {
    const auto truth = renderer.truth(f);
    if (f == 180) tracker.reset();  // the cut
    cv::Mat grey;
    cv::cvtColor(renderer.render(f), grey, cv::COLOR_BGR2GRAY);
    const auto sf = tracker.update(detector->detect(grey), script.camera, f, truth.time);
    r.drawnOff10 +=
        sf.planetCentreValid && (sf.planetCentreCamera - truth.planetCentreCamera).norm() > 0.01;
    r.visible += truth.planetVisible;
    r.measured += truth.planetVisible && sf.planet.measured;
    for (const auto& n : sf.notes) r.covered += n.find("the tool covers") != std::string::npos;
  }
  return r;
}

}  // namespace

// A single planet marker whose corner the tool's stick or card covers still decodes, and its
// dragged corner gives the planar pose's mirror image (the sweep drew 14 frames 20-45 mm off
// here). While covered it is used only when its pose stays with the planet's; otherwise it is
// held and then lost, and measured again once clear.
TEST(TrackingOcclusion, APlanetMarkerUnderTheToolIsNotDrawnFlipped) {
  const SweepRun without = replaySweepShots(0);
  ASSERT_GE(without.drawnOff10, 5) << "the shots draw the covered marker's mirror image";
  const SweepRun with = replaySweepShots(tracking::SceneConfig{}.toolCoverBandCells);
  EXPECT_EQ(with.drawnOff10, 0);
  EXPECT_GE(with.covered, 5) << "covered detections not used";
  ASSERT_GE(with.visible, 5);
  EXPECT_EQ(with.measured, with.visible) << "an uncovered marker is measured";
}

// The plane tracker on a textured plane seen through a known camera path (each frame the plane's
// texture warped by its homography): the board's pose it carries stays within 2 mm and 0.3
// degrees of the truth for 24 frames, at full resolution and on the half-size frame (its
// default; corners found there are mapped back to full-resolution pixels for the pose).
TEST(TrackingOcclusion, PlaneTrackerCarriesAPoseAtFullAndHalfSize) {
  const auto cam = tracking::CameraCalibration::pinhole(600, 600, 319.5, 239.5, {640, 480});
  const cv::Mat table = texture({1600, 1200}, 7);  // 0.5 mm a pixel, centred on the origin
  const cv::Matx33d fromTexture(0.0005, 0, -0.4, 0, 0.0005, -0.3, 0, 0, 1);
  auto view = [&](const tracking::Pose& board) {
    const Eigen::Matrix3d& R = board.R;
    const cv::Matx33d Rt(R(0, 0), R(0, 1), board.t.x(), R(1, 0), R(1, 1), board.t.y(), R(2, 0),
                         R(2, 1), board.t.z());
    cv::Mat out;
    cv::warpPerspective(table, out, cv::Mat(cam.K * Rt * fromTexture), cam.imageSize,
                        cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(120));
    return out;
  };
  auto boardAt = [](int k) {
    return tracking::Pose::fromRvecTvec({M_PI + 0.4 + 0.004 * k, 0.1 - 0.003 * k, 0.2 + 0.002 * k},
                                        {0.01 - 0.002 * k, 0.02 + 0.0015 * k, 0.6 - 0.002 * k});
  };
  for (int downscale : {1, 2}) {
    tracking::PlaneTrackerConfig c;
    c.downscale = downscale;
    tracking::PlaneTracker tracker(c);
    tracker.setReference(view(boardAt(0)), boardAt(0), {});
    for (int k = 1; k <= 24; ++k) {
      const tracking::PlaneTrack r = tracker.track(view(boardAt(k)), cam);
      ASSERT_TRUE(r.ok) << "downscale " << downscale << ", frame " << k << ": " << r.why;
      EXPECT_GE(r.inliers, 40);
      EXPECT_LT((r.board.t - boardAt(k).t).norm(), 2e-3) << downscale << ", frame " << k;
      EXPECT_LT(tracking::rotationAngle(r.board.R, boardAt(k).R), 0.3 * M_PI / 180)
          << downscale << ", frame " << k;
    }
  }
  tracking::PlaneTrackerConfig bad;
  bad.downscale = 0;
  EXPECT_THROW(tracking::PlaneTracker{bad}, core::InputError);
  bad = {};
  bad.gridRows = 0;
  EXPECT_THROW(tracking::PlaneTracker{bad}, core::InputError);
}
