// Benchmark plots: the files appear, with one panel per quantity, and the measured points are
// drawn where the axes put them (a series' colour at its point, the bound dashed in dark grey).
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "app/bench_plots.hpp"
#include "app/plot.hpp"

using namespace ps;

TEST(BenchPlots, WritesOnePlotPerBenchmarkWithTheBound) {
  std::vector<nlohmann::json> records;
  for (double d : {0.5, 1.0, 2.0, 4.0})
    records.push_back({{"bench", "tessellate"},
                       {"view", "orbit"},
                       {"grid", "513x513"},
                       {"dist_max", d},
                       {"max_screen_error_px", 0.8 * d},
                       {"ms", 4.0 / d},
                       {"triangles", 10000 / d}});
  records.push_back({{"bench", "erosion"},
                     {"method", "thermal"},
                     {"grid", "513x513"},
                     {"threads", 1},
                     {"cell_steps_per_s", 9e7},
                     {"ms_per_step", 3.0},
                     {"volume_drift", 0.0}});
  records.push_back({{"bench", "unknown"}, {"x", 1}});
  const auto dir = std::filesystem::temp_directory_path() / "ps_bench_plots";
  std::filesystem::remove_all(dir);
  const auto files = app::writeBenchPlots(records, dir);
  ASSERT_EQ(files.size(), 2u);
  const cv::Mat t = cv::imread((dir / "tessellate.png").string());
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t.cols, 3 * 560);
  EXPECT_EQ(t.rows, 420);
  // The first series' colour appears in each of the three panels.
  const cv::Scalar c = app::seriesColour(0);
  for (int panel = 0; panel < 3; ++panel) {
    cv::Mat mask;
    cv::inRange(t(cv::Rect(panel * 560, 40, 560, 330)), c - cv::Scalar::all(2),
                c + cv::Scalar::all(2), mask);
    EXPECT_GT(cv::countNonZero(mask), 30) << "panel " << panel;
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "erosion.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "track.png"));
  std::filesystem::remove_all(dir);
}

TEST(BenchPlots, PointsLandWhereTheAxesSay) {
  app::PlotPanel p{"t", "x", "y", false, false, {}};
  app::PlotSeries s;
  s.x = {0, 10};
  s.y = {0, 10};
  s.lines = false;
  s.colour = cv::Scalar(0, 0, 255);
  p.series.push_back(s);
  const cv::Mat img = app::drawPlots({p}, 400, 300);
  // Box: left 70, right 16, top 44, bottom 52 -> (70, 44)-(384, 248); y axis from 0, x from 0;
  // the top end is padded by 5 %: 10 sits at 1/1.05 of the box.
  const double bx = 70 + (384 - 70) * (10 / 10.5), by = 248 - (248 - 44) * (10 / 10.5);
  const cv::Vec3b at = img.at<cv::Vec3b>(int(std::lround(by)), int(std::lround(bx)));
  EXPECT_EQ(at, cv::Vec3b(0, 0, 255));
  const cv::Vec3b origin = img.at<cv::Vec3b>(248, 70);
  EXPECT_EQ(origin, cv::Vec3b(0, 0, 255));
}
