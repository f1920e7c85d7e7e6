// Stress tests for tracking (issue 9): degenerate frames - markers seen edge-on, tiny, heavily
// blurred, half occluded, overlapping, all black or white, noise only, 1x1 and odd sizes, frames
// of the wrong type (made in degenerate_frames.hpp) - through both detector back ends, the scene
// tracker and the FrameStepper.
// What must hold: no crash; a wrong image type is refused with core::InputError (or, for colour,
// converted); no NaN/inf corner, pose or tip is ever reported as tracked; and nothing non-finite
// reaches the edit pipeline: the planet's heights stay finite, and bit-for-bit unchanged in every
// frame where no touching tool is reported. Frames come from the synthetic renderer (synth.hpp)
// at 320x240 (the short scene's camera). Seeded and deterministic; PS_STRESS_SCALE multiplies
// the random parts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <typeinfo>
#include <vector>

#include "core/input_error.hpp"
#include "degenerate_frames.hpp"
#include "replay/replay.hpp"
#include "short_scene.hpp"
#include "stress_util.hpp"
#include "test_terrains.hpp"
#include "tracking/detector.hpp"
#include "tracking/pose.hpp"
#include "tracking/synth.hpp"
#include "tracking/tracker.hpp"

using namespace ps;
using namespace ps::stresstest;

namespace {

bool finiteCorners(const std::array<cv::Point2d, 4>& c) {
  return std::all_of(c.begin(), c.end(),
                     [](const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); });
}

bool rotation(const Eigen::Matrix3d& R) {
  return R.allFinite() && (R * R.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-6) &&
         R.determinant() > 0;
}

// What a tracked (or held) marker may report: a finite rotation and translation, in front of
// the camera.
void expectSaneMarker(const tracking::MarkerEstimate& m, const std::string& where) {
  if (m.measured) {
    EXPECT_TRUE(m.raw.finite() && rotation(m.raw.R)) << where;
    EXPECT_TRUE(finiteCorners(m.corners)) << where;
    EXPECT_TRUE(std::isfinite(m.rms)) << where;
    EXPECT_EQ(m.state, tracking::TrackState::kTracked) << where;
  }
  if (m.usable()) {
    EXPECT_TRUE(m.pose.finite()) << where << ": " << m.pose.t.transpose();
    EXPECT_TRUE(rotation(m.pose.R)) << where;
    EXPECT_GT(m.pose.t.z(), 0.0) << where;
  }
}

void expectSaneScene(const tracking::SceneFrame& f, const std::string& where) {
  expectSaneMarker(f.planet, where + " (planet)");
  expectSaneMarker(f.tool, where + " (tool)");
  if (f.tipValid) {
    EXPECT_TRUE(f.planet.usable() && f.tool.usable()) << where;
    EXPECT_TRUE(f.tipCamera.allFinite()) << where;
    EXPECT_TRUE(f.tipPlanet.allFinite()) << where;
    EXPECT_TRUE(std::isfinite(f.tipHeight)) << where;
  }
  if (f.touching) {
    EXPECT_TRUE(f.tipValid) << where;
  }
}

// Runs the detector on a case: detections with finite corners and the wanted ids, or (for a
// refused type only) core::InputError. Anything else - another exception, a crash - fails.
std::vector<tracking::Detection> detectCase(tracking::Detector& d, const Case& c,
                                            const std::string& where) {
  std::vector<tracking::Detection> found;
  try {
    found = d.detect(c.image);
    EXPECT_FALSE(c.refused) << where << ": a " << c.name << " image was not refused";
  } catch (const core::InputError& e) {
    EXPECT_TRUE(c.refused) << where << ": " << e.what();
    EXPECT_GT(std::strlen(e.what()), 5u) << where;
  } catch (const std::exception& e) {
    ADD_FAILURE() << where << ": " << typeid(e).name() << ": " << e.what();
  }
  for (const auto& x : found) {
    EXPECT_TRUE(finiteCorners(x.corners)) << where;
    EXPECT_TRUE(x.id == 0 || x.id == 1) << where << ": id " << x.id;
    EXPECT_TRUE(std::isfinite(x.decisionMargin)) << where;
  }
  if (!c.toolPossible) {
    EXPECT_TRUE(found.empty()) << where << ": " << found.size() << " marker(s) in a " << c.name
                               << " frame";
  }
  return found;
}

struct BackEnd {
  const char* name;
  tracking::Backend backend;
};
constexpr BackEnd kBackEnds[] = {{"apriltag", tracking::Backend::kAprilTag},
                                 {"aruco", tracking::Backend::kAruco}};

tracking::DetectorConfig detectorConfig(tracking::Backend b, bool regions) {
  tracking::DetectorConfig c;
  c.backend = b;
  c.regions = regions;
  c.ids = {0, 1};
  return c;
}

bool allFinite(std::span<const float> h) {
  return std::all_of(h.begin(), h.end(), [](float x) { return std::isfinite(x); });
}

}  // namespace

// Every degenerate frame straight into each back end (plain and with region tracking): corners
// finite, the right ids, wrong types refused with InputError; a region-tracking detector that
// has just seen a degenerate frame finds both markers again in the next good frames.
TEST(StressTracking, DegenerateFramesThroughBothDetectorBackEnds) {
  const auto& all = cases();
  const cv::Mat& good = all.front().image;
  ASSERT_EQ(all.front().name, "good");
  for (const BackEnd& be : kBackEnds) {
    for (bool regions : {false, true}) {
      auto det = tracking::makeDetector(detectorConfig(be.backend, regions));
      const std::string who = std::string(be.name) + (regions ? " + regions" : "");
      // The good frame: both markers (the scene works with this back end at all).
      const auto base = det->detect(good);
      ASSERT_EQ(base.size(), 2u) << who;
      int recovered = 0;
      for (const Case& c : all) {
        const std::string where = who + ", " + c.name;
        detectCase(*det, c, where);
        // Back to the good frame: found again within searchEvery frames.
        bool both = false;
        for (int k = 0; k < 3 && !both; ++k) both = det->detect(good).size() == 2;
        EXPECT_TRUE(both) << where << ": markers not found again";
        recovered += both;
      }
      RecordProperty(be.name + std::string(regions ? "_regions" : "") + "_recovered",
                     std::to_string(recovered));
    }
  }
}

// The AprilTag library crashed (SIGSEGV; SIGFPE at decimate 1.5) on images whose decimated
// quad-search image is under 3 pixels on a side: a 1x1 frame, slivers, 8x8 at decimate 4. Every
// size from 1x1 to 26x26 (and slivers of a full frame) at every decimate the settings allow a
// sample of: no crash, no marker.
TEST(StressTracking, AprilTagSurvivesTinyImagesAtAnyDecimate) {
  cv::RNG rng(5);
  for (double decimate : {1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 8.0}) {
    tracking::DetectorConfig c;
    c.backend = tracking::Backend::kAprilTag;
    c.regions = false;
    c.decimate = decimate;
    auto det = tracking::makeDetector(c);
    std::vector<cv::Size> sizes;
    for (int w = 1; w <= 26; ++w)
      for (int h = 1; h <= 26; ++h) sizes.emplace_back(w, h);
    for (int k = 1; k <= 4; ++k) {
      sizes.emplace_back(320, k);
      sizes.emplace_back(k, 240);
    }
    for (const cv::Size& s : sizes) {
      cv::Mat m(s, CV_8U);
      rng.fill(m, cv::RNG::UNIFORM, 0, 256);
      EXPECT_TRUE(det->detect(m).empty()) << s << " at decimate " << decimate;
    }
  }
}

// The aruco back end with each of its corner refinements on tiny images and on every degenerate
// frame: no crash and no stray exception (OpenCV 4.6's AprilTag refinement threw an assertion,
// resize with an empty size, for images with a 1-pixel side), nothing outside the wanted ids,
// finite corners, wrong types refused with InputError.
TEST(StressTracking, ArucoSurvivesTinyAndDegenerateImagesWithEveryRefinement) {
  cv::RNG rng(6);
  for (auto refinement :
       {tracking::ArucoRefinement::kNone, tracking::ArucoRefinement::kSubpix,
        tracking::ArucoRefinement::kContour, tracking::ArucoRefinement::kAprilTag}) {
    tracking::DetectorConfig c = detectorConfig(tracking::Backend::kAruco, false);
    c.arucoRefinement = refinement;
    auto det = tracking::makeDetector(c);
    const std::string who = "aruco " + tracking::toString(refinement);
    for (int w = 1; w <= 26; w += (w < 10 ? 1 : 4)) {
      for (int h = 1; h <= 26; h += (h < 10 ? 1 : 4)) {
        cv::Mat m(h, w, CV_8U);
        rng.fill(m, cv::RNG::UNIFORM, 0, 256);
        EXPECT_TRUE(det->detect(m).empty()) << who << ", " << w << "x" << h;
      }
    }
    for (const Case& k : cases()) detectCase(*det, k, who + ", " + k.name);
  }
}

// Degenerate frames, each several times in a row, interleaved with good frames through the
// scene tracker (fed by each back end): no non-finite pose or tip is ever reported, poses that
// are held stay the last good ones, and after the hold time a frame with no marker reports lost.
TEST(StressTracking, SceneTrackerNeverReportsANonFinitePoseOrTip) {
  const auto& all = cases();
  const auto opts = testkit::shortSceneOptions();
  const auto calib = testkit::shortSceneCamera();
  for (const BackEnd& be : kBackEnds) {
    auto det = tracking::makeDetector(detectorConfig(be.backend, true));
    tracking::SceneTracker scene(opts.scene);
    int frame = 0, lostAfterHold = 0, tracked = 0, held = 0;
    tracking::Pose lastPlanet, lastTool;
    auto step = [&](const Case& c, const std::string& where) {
      std::vector<tracking::Detection> found;
      try {
        found = det->detect(c.image);
      } catch (const core::InputError&) {
      }
      const double time = frame / 30.0;
      const auto f = scene.update(found, calib, frame++, time);
      expectSaneScene(f, where);
      // A held pose is the last tracked one, exactly.
      for (auto [m, last] : {std::pair{&f.planet, &lastPlanet}, std::pair{&f.tool, &lastTool}}) {
        if (m->state == tracking::TrackState::kTracked) *last = m->pose;
        if (m->state == tracking::TrackState::kHeld) {
          EXPECT_TRUE(m->pose.R == last->R && m->pose.t == last->t) << where;
          ++held;
        }
      }
      tracked += f.planet.state == tracking::TrackState::kTracked;
      return f;
    };
    for (const Case& c : all) {
      for (int k = 0; k < 4; ++k) step(all.front(), "good");
      // 12 frames (0.4 s): longer than the 0.25 s hold.
      for (int k = 0; k < 12; ++k) {
        const auto f = step(c, std::string(be.name) + ", " + c.name + " #" + std::to_string(k));
        if (!c.toolPossible && k >= 8) {
          EXPECT_EQ(f.tool.state, tracking::TrackState::kLost) << c.name;
          EXPECT_EQ(f.planet.state, tracking::TrackState::kLost) << c.name;
          EXPECT_FALSE(f.tipValid) << c.name;
          lostAfterHold += !f.tipValid;
        }
      }
    }
    EXPECT_GT(lostAfterHold, 0);
    EXPECT_GT(held, 0);
    EXPECT_GT(tracked, int(all.size()) * 4);  // the good frames between were tracked
  }
}

// Random corners straight into the scene tracker: collinear, coincident, self-intersecting,
// reversed, sub-pixel, huge, outside the image, NaN and inf, duplicated ids. Whatever the pose
// solver makes of them, a pose reported as tracked or held and a tip reported valid are finite.
TEST(StressTracking, RandomCornersNeverGiveANonFinitePoseOrTip) {
  const auto opts = testkit::shortSceneOptions();
  const auto calib = testkit::shortSceneCamera();
  tracking::SceneTracker scene(opts.scene);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u01(0, 1), px(-40, 360);
  const double specials[] = {kNaN, kInf, -kInf, 1e300, -1e300, 1e12, -1e12, 0.0, 1e-300};
  const int n = 4000 * testkit::stressScale();
  int measured = 0, touching = 0;
  double time = 0;
  for (int k = 0; k < n; ++k) {
    std::vector<tracking::Detection> dets;
    const int count = int(u01(rng) * 4);
    for (int i = 0; i < count; ++i) {
      tracking::Detection d;
      d.id = u01(rng) < 0.45 ? 0 : (u01(rng) < 0.9 ? 1 : 7);
      const double kind = u01(rng);
      const cv::Point2d c(px(rng), px(rng) * 0.75);
      const double s = std::exp(std::log(1e-6) + u01(rng) * std::log(1e9));  // 1e-6 .. 1e3 px
      const double a = u01(rng) * 6.3;
      for (int j = 0; j < 4; ++j) {
        // A square (TL, TR, BR, BL clockwise on screen), perturbed by the kind of damage.
        const double ang = a + j * 1.5707963267948966;
        d.corners[std::size_t(j)] = c + s * cv::Point2d(std::cos(ang), std::sin(ang));
      }
      if (kind < 0.1) {
        for (auto& p : d.corners) p = c;  // one point
      } else if (kind < 0.2) {
        for (int j = 0; j < 4; ++j) d.corners[std::size_t(j)] = c + j * s * cv::Point2d(1, 0.3);
      } else if (kind < 0.3) {
        std::swap(d.corners[1], d.corners[2]);  // bow tie
      } else if (kind < 0.4) {
        std::reverse(d.corners.begin(), d.corners.end());  // mirrored
      } else if (kind < 0.5) {
        for (auto& p : d.corners) p = {px(rng), px(rng)};  // any quad
      } else if (kind < 0.6) {
        auto& p = d.corners[std::size_t(u01(rng) * 4) % 4];
        (u01(rng) < 0.5 ? p.x : p.y) = specials[std::size_t(u01(rng) * 9) % 9];
      } else if (kind < 0.65) {
        for (auto& p : d.corners) p *= 1e9;
      }
      dets.push_back(d);
    }
    // Time mostly advancing by a frame, sometimes stalling or stepping back.
    const double r = u01(rng);
    time += r < 0.9 ? 1.0 / 30 : (r < 0.95 ? 0.0 : -0.02);
    const auto f = scene.update(dets, calib, k, time);
    expectSaneScene(f, "update " + std::to_string(k));
    if (::testing::Test::HasFailure()) return;
    measured += f.planet.measured + f.tool.measured;
    touching += f.touching;
  }
  EXPECT_GT(measured, n / 10);  // the solver really produced poses to check
  RecordProperty("touching_updates", std::to_string(touching));
}

namespace {

// Replays `frames` (each with its time) through a fresh FrameStepper with `backend` on a small
// bumpy planet, checking after every frame that nothing non-finite was reported or reached the
// heights, and that the heights did not change unless a touching tool was reported.
struct StepCheck {
  terrain::Terrain planet = testkit::bumpyTerrain(7, 4, 3000.0);
  std::vector<float> initial = std::vector<float>(planet.heights().begin(), planet.heights().end());
  std::vector<float> before = initial;
  replay::FrameStepper stepper;

  explicit StepCheck(tracking::Backend backend)
      : stepper(testkit::shortSceneCamera().forImageSize(kSize), planet, options(backend)) {}
  static replay::ReplayOptions options(tracking::Backend backend) {
    auto o = testkit::shortSceneOptions();
    o.detector.backend = backend;
    return o;
  }

  replay::StepResult step(const cv::Mat& image, int frame, const std::string& where) {
    const auto r = stepper.step(image, frame, frame / 30.0);
    expectSaneScene(r.scene, where);
    if (r.planetInCamera) {
      EXPECT_TRUE(r.planetInCamera->finite()) << where;
    }
    // nlohmann writes a non-finite number as null: none may reach the log.
    EXPECT_EQ(r.logLine.find("null"), std::string::npos) << where << ": " << r.logLine;
    const auto h = planet.heights();
    if (r.touching) {
      EXPECT_TRUE(r.scene.tipValid && r.scene.tipPlanet.allFinite()) << where;
      EXPECT_TRUE(r.control.has_value()) << where;
      if (r.control) {
        EXPECT_TRUE(r.control->u >= 0 && r.control->u <= planet.grid().m() && r.control->v >= 0 &&
                    r.control->v <= planet.grid().m())
            << where;
      }
    } else {
      EXPECT_EQ(std::memcmp(h.data(), before.data(), h.size() * sizeof(float)), 0)
          << where << ": heights changed with no touching tool";
    }
    EXPECT_TRUE(allFinite(h)) << where;
    before.assign(h.begin(), h.end());
    return r;
  }
  bool unchanged() const {
    return std::memcmp(planet.heights().data(), initial.data(), initial.size() * sizeof(float)) ==
           0;
  }
};

}  // namespace

// Through the FrameStepper (detector -> scene -> control vertex -> brush -> edit pipeline), with
// each back end, a stepper that only ever sees degenerate frames, 6 of each kind in a row: first
// every kind in which no marker can be seen (blank, noise, a few pixels, refused types), where it
// must never report a marker or touch and must leave the planet bit-for-bit as it was (and, for
// a refused image type, say in the log why it saw nothing); then the rendered and overlapping
// views, where whatever it tracks it reports nothing non-finite and edits only while touching.
TEST(StressTracking, StepperFedOnlyDegenerateFramesEditsNothingWithoutATool) {
  std::vector<const Case*> order;
  for (const Case& c : cases())
    if (!c.toolPossible) order.push_back(&c);
  const std::size_t blind = order.size();
  for (const Case& c : cases())
    if (c.toolPossible && c.name != "good") order.push_back(&c);
  for (const BackEnd& be : kBackEnds) {
    StepCheck run(be.backend);
    int frame = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      const Case& c = *order[i];
      const std::string where = std::string(be.name) + ", only degenerate frames, " + c.name;
      for (int k = 0; k < 6; ++k) {
        const auto r = run.step(c.image, frame++, where);
        if (i < blind) {
          EXPECT_FALSE(r.scene.planet.usable() || r.scene.tool.usable()) << where;
          EXPECT_FALSE(r.touching) << where;
        }
        if (c.refused) {
          EXPECT_NE(r.logLine.find("detection failed"), std::string::npos) << r.logLine;
        }
      }
      if (i + 1 == blind) {
        EXPECT_EQ(run.stepper.summary().touchingFrames, 0) << be.name;
        EXPECT_TRUE(run.unchanged()) << be.name;
      }
      if (::testing::Test::HasFailure()) return;
    }
    run.stepper.endStroke();
    const auto& s = run.stepper.summary();
    std::cerr << be.name << ", only degenerate frames: " << s.frames << " frames, "
              << s.framesWithPlanet << " with the planet, " << s.framesWithTool
              << " with the tool, " << s.touchingFrames << " touching\n";
  }
}

// The property that matters, while the tool really sculpts: one stepper per back end replays
// the short scene (the tool comes down and draws a stroke) with a burst of 10 degenerate frames
// of each kind after every 5 scene frames. Every frame: nothing non-finite in the scene, the
// AR pose, the control vertex or the log; the heights stay finite and are bit-for-bit unchanged
// in every frame that reports no touching tool. A held tool may go on touching for the 0.25 s
// hold; once a burst without any marker has outlived it, the tool is lost and nothing touches.
// Between the bursts the scene is tracked again and sculpts.
TEST(StressTracking, DegenerateFramesNeverReachTheEditPipeline) {
  auto script = tracking::builtinScene("short");
  script.colour = false;
  const tracking::SynthRenderer shortScene(script);
  std::vector<cv::Mat> scene;
  for (int f = 0; f < shortScene.frames(); ++f) scene.push_back(shortScene.render(f));
  for (const BackEnd& be : kBackEnds) {
    StepCheck run(be.backend);
    int frame = 0, goodFrame = 0, lostChecked = 0;
    for (const Case& c : cases()) {
      for (int k = 0; k < 5; ++k, ++frame)
        run.step(scene[std::size_t(goodFrame++ % int(scene.size()))], frame,
                 std::string(be.name) + ", scene frame before " + c.name);
      for (int k = 0; k < 10; ++k, ++frame) {
        const std::string where =
            std::string(be.name) + ", burst of " + c.name + " #" + std::to_string(k);
        const auto r = run.step(c.image, frame, where);
        if (!c.toolPossible && k >= 8) {  // 0.27 s and more after the last scene frame
          EXPECT_FALSE(r.scene.tool.usable()) << where;
          EXPECT_FALSE(r.touching) << where;
          ++lostChecked;
        }
      }
      if (::testing::Test::HasFailure()) return;
    }
    run.stepper.endStroke();
    const auto& s = run.stepper.summary();
    EXPECT_GE(s.strokes, 10) << be.name;  // the tool really sculpted between the bursts
    EXPECT_GT(s.modifiedVertices, 0u) << be.name;
    EXPECT_FALSE(run.unchanged()) << be.name;
    EXPECT_GT(lostChecked, 40) << be.name;
    std::cerr << be.name << ": " << s.frames << " frames, " << s.touchingFrames << " touching, "
              << s.strokes << " strokes, " << s.framesWithTip << " with a tip\n";
  }
}
