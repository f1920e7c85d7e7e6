#pragma once
// Small 2D charts drawn with OpenCV (lines, points, log or linear axes, a legend) for benchmark
// results people would rather look at than read.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ps::app {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  cv::Scalar colour{200, 80, 30};
  bool lines = true;    // join the points in order
  bool dashed = false;  // a bound or a reference, not a measurement
};

struct PlotPanel {
  std::string title, xLabel, yLabel;
  bool logX = false, logY = false;
  std::vector<PlotSeries> series;
};

// Panels side by side, each width x height. Non-finite points (and non-positive ones on a log
// axis) are skipped.
cv::Mat drawPlots(const std::vector<PlotPanel>& panels, int width = 560, int height = 420);

// Distinct colours for series i = 0, 1, ...
cv::Scalar seriesColour(std::size_t i);

}  // namespace ps::app
