#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "core/input_error.hpp"
#include "replay/truth_check.hpp"

namespace ps {
namespace {

using nlohmann::json;

json truthFrame(int frame, bool touching, double tipX, int halfVisible) {
  return {{"type", "frame"},
          {"frame", frame},
          {"touching", touching},
          {"tip_planet", {tipX, 0.0, 0.05}},
          {"tool", {{"visible", true}}},
          {"planet", {{"half_visible", halfVisible}, {"centre_camera_m", {0.0, 0.0, 0.6}}}}};
}

json logFrame(int frame, bool touching, double tipX, const std::string& state) {
  json j = {{"frame", frame},
            {"touching", touching},
            {"tip_planet_m", {tipX, 0.0, 0.05}},
            {"planet", {{"state", state}, {"centre_camera_m", {0.0, 0.001, 0.6}}}}};
  return j;
}

std::string lines(const std::vector<json>& js) {
  std::string s;
  for (const auto& j : js) s += j.dump() + "\n";
  return s;
}

TEST(ReplayTruth, CountsTouchingFramesPosesAndErrorsFrameByFrame) {
  std::vector<json> truth = {{{"frames", 5}, {"script", json::object()}}};  // the header
  std::vector<json> log;
  // Frames 0-3 in both; frame 4 only in the truth (a truncated replay).
  truth.push_back(truthFrame(0, false, 0.010, 9));
  log.push_back(logFrame(0, false, 0.0101, "tracked"));  // 0.1 mm off
  truth.push_back(truthFrame(1, true, 0.020, 3));
  log.push_back(logFrame(1, true, 0.0205, "tracked"));  // 0.5 mm
  truth.push_back(truthFrame(2, true, 0.030, 0));       // board hidden
  log.push_back(logFrame(2, false, 0.0330, "held"));    // 3 mm, not sculpted
  truth.push_back(truthFrame(3, true, 0.040, 1));
  log.push_back(logFrame(3, false, 0.040, "lost"));
  truth.push_back(truthFrame(4, true, 0.050, 9));
  std::istringstream t(lines(truth)), l(lines(log));
  const auto c = replay::compareWithTruth(t, "v.truth.jsonl", l, "log.jsonl");
  EXPECT_EQ(c.frames, 4);
  EXPECT_EQ(c.touching, 3);
  EXPECT_EQ(c.sculptedWhenTouching, 1);
  EXPECT_EQ(c.planetVisible, 3);    // frames 0, 1, 3
  EXPECT_EQ(c.poseWhenVisible, 2);  // frame 3 was lost
  ASSERT_TRUE(c.tipErrorMm.is_object());
  EXPECT_EQ(c.tipErrorMm["frames"], 4);
  EXPECT_NEAR(c.tipErrorMm["median"].get<double>(), 0.1, 1e-9);  // 0, 0.1, 0.5, 3: the 2nd
  EXPECT_NEAR(c.tipErrorMm["max"].get<double>(), 3.0, 1e-9);
  ASSERT_TRUE(c.centreErrorMm.is_object());
  EXPECT_EQ(c.centreErrorMm["frames"], 3);  // not where the pose was lost
  EXPECT_NEAR(c.centreErrorMm["p95"].get<double>(), 1.0, 1e-9);
  EXPECT_EQ(c.toJson()["sculpted_when_touching"], 1);
}

TEST(ReplayTruth, ASingleMarkerIsInViewWhenTheTruthSaysItIsVisible) {
  json t0 = {{"frame", 0}, {"planet", {{"visible", true}}}};
  json t1 = {{"frame", 1}, {"planet", {{"visible", false}}}};
  std::istringstream t(lines({t0, t1})),
      l(lines({logFrame(0, false, 0, "tracked"), logFrame(1, false, 0, "held")}));
  const auto c = replay::compareWithTruth(t, "t", l, "l");
  EXPECT_EQ(c.planetVisible, 1);
  EXPECT_EQ(c.poseWhenVisible, 1);
  EXPECT_TRUE(c.tipErrorMm.is_null());  // no tip in this truth
}

TEST(ReplayTruth, ALineThatIsNotJsonIsRefusedNamingTheFileAndLine) {
  std::istringstream t("{\"frame\": 0}\n{\"frame\": 1\n"), l("");
  try {
    replay::compareWithTruth(t, "demo.truth.jsonl", l, "log.jsonl");
    FAIL() << "accepted a broken line";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("demo.truth.jsonl:2"), std::string::npos) << e.what();
  }
  std::istringstream t2("{\"frame\": \"zero\"}\n"), l2("");
  EXPECT_THROW(replay::compareWithTruth(t2, "t", l2, "l"), core::InputError);
}

TEST(ReplayTruth, TheTruthFileLiesBesideTheVideo) {
  EXPECT_EQ(replay::truthPathFor("data/demo.mkv"), "data/demo.truth.jsonl");
}

}  // namespace
}  // namespace ps
