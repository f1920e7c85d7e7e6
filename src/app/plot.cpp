#include "app/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace ps::app {

namespace {

struct Axis {
  double lo = 0, hi = 1;
  bool log = false;
  double map(double v) const {
    const double a = log ? std::log10(v) : v, l = log ? std::log10(lo) : lo,
                 h = log ? std::log10(hi) : hi;
    return (a - l) / (h - l);
  }
};

bool usable(double v, bool log) {
  return std::isfinite(v) && (!log || v > 0);
}

Axis axisFor(const std::vector<PlotSeries>& series, bool useX, bool log) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series)
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      const double v = useX ? s.x[i] : s.y[i];
      if (!usable(s.x[i], false) || !usable(s.y[i], false) || !usable(v, log)) continue;
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
  if (!std::isfinite(lo)) lo = log ? 1 : 0, hi = log ? 10 : 1;
  Axis a;
  a.log = log;
  if (log) {
    a.lo = std::pow(10, std::floor(std::log10(lo)));
    a.hi = std::pow(10, std::ceil(std::log10(hi)));
    if (a.hi <= a.lo) a.hi = a.lo * 10;
  } else {
    const double pad = hi > lo ? 0.05 * (hi - lo) : std::max(1e-9, std::abs(hi) * 0.1 + 1e-9);
    a.lo = lo - pad;
    if (lo >= 0 && a.lo < 0) a.lo = 0;  // non-negative data starts at zero, not below
    a.hi = hi + pad;
  }
  return a;
}

std::string tickText(double v) {
  char b[32];
  const double a = std::abs(v);
  if (a != 0 && (a >= 1e5 || a < 1e-2))
    std::snprintf(b, sizeof b, "%.0e", v);
  else
    std::snprintf(b, sizeof b, "%g", std::round(v * 1000) / 1000);
  return b;
}

std::vector<double> ticks(const Axis& a) {
  std::vector<double> t;
  if (a.log) {
    for (double v = a.lo; v <= a.hi * 1.0001; v *= 10) t.push_back(v);
    return t;
  }
  const double span = a.hi - a.lo;
  const double raw = span / 5, mag = std::pow(10, std::floor(std::log10(raw)));
  const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
  for (double v = std::ceil(a.lo / step) * step; v <= a.hi + 1e-9 * span; v += step)
    t.push_back(std::abs(v) < 1e-12 * step ? 0 : v);
  return t;
}

void drawPlotPanel(cv::Mat img, const PlotPanel& p) {
  const int W = img.cols, H = img.rows;
  const int left = 70, right = 16, top = 44, bottom = 52;
  const cv::Rect box(left, top, W - left - right, H - top - bottom);
  const Axis ax = axisFor(p.series, true, p.logX), ay = axisFor(p.series, false, p.logY);
  auto px = [&](double x, double y) {
    return cv::Point2d(box.x + ax.map(x) * box.width, box.y + (1 - ay.map(y)) * box.height);
  };
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(img, p.title, {left, 18}, font, 0.5, {20, 20, 20}, 1, cv::LINE_AA);
  for (double t : ticks(ax)) {
    const int x = int(std::lround(px(t, ay.lo).x));
    cv::line(img, {x, box.y}, {x, box.y + box.height}, {230, 230, 230}, 1);
    cv::putText(img, tickText(t), {x - 14, box.y + box.height + 16}, font, 0.38, {60, 60, 60}, 1,
                cv::LINE_AA);
  }
  for (double t : ticks(ay)) {
    const int y = int(std::lround(px(ax.lo, t).y));
    cv::line(img, {box.x, y}, {box.x + box.width, y}, {230, 230, 230}, 1);
    cv::putText(img, tickText(t), {4, y + 4}, font, 0.38, {60, 60, 60}, 1, cv::LINE_AA);
  }
  cv::rectangle(img, box, {90, 90, 90}, 1);
  cv::putText(img, p.xLabel, {box.x + box.width / 2 - 4 * int(p.xLabel.size()), H - 12}, font, 0.42,
              {20, 20, 20}, 1, cv::LINE_AA);
  // The y label goes above the axis, left-aligned (OpenCV cannot rotate text).
  cv::putText(img, p.yLabel, {4, top - 6}, font, 0.4, {20, 20, 20}, 1, cv::LINE_AA);
  int legendY = box.y + 14;
  for (const auto& s : p.series) {
    std::vector<cv::Point> pts;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!usable(s.x[i], p.logX) || !usable(s.y[i], p.logY)) continue;
      const cv::Point2d q = px(s.x[i], s.y[i]);
      pts.emplace_back(int(std::lround(q.x)), int(std::lround(q.y)));
    }
    if (s.lines && pts.size() > 1) {
      for (std::size_t i = 1; i < pts.size(); ++i) {
        if (!s.dashed) {
          cv::line(img, pts[i - 1], pts[i], s.colour, 2, cv::LINE_AA);
          continue;
        }
        const cv::Point2d a = pts[i - 1], b = pts[i];
        const double len = cv::norm(b - a);
        for (double t = 0; t < len; t += 12) {
          const double t2 = std::min(len, t + 6);
          cv::line(img, a + (b - a) * (t / len), a + (b - a) * (t2 / len), s.colour, 2,
                   cv::LINE_AA);
        }
      }
    }
    if (!s.dashed)
      for (const auto& q : pts) cv::circle(img, q, 3, s.colour, cv::FILLED, cv::LINE_AA);
    if (!s.label.empty()) {
      cv::line(img, {box.x + 8, legendY - 4}, {box.x + 26, legendY - 4}, s.colour, 2, cv::LINE_AA);
      cv::putText(img, s.label, {box.x + 32, legendY}, font, 0.38, {30, 30, 30}, 1, cv::LINE_AA);
      legendY += 15;
    }
  }
}

}  // namespace

cv::Scalar seriesColour(std::size_t i) {
  static const cv::Scalar palette[] = {{180, 100, 30}, {40, 120, 230}, {60, 160, 60},
                                       {40, 40, 200},  {160, 80, 160}, {30, 160, 190},
                                       {120, 120, 120}};
  return palette[i % std::size(palette)];
}

cv::Mat drawPlots(const std::vector<PlotPanel>& panels, int width, int height) {
  cv::Mat img(height, width * int(std::max<std::size_t>(1, panels.size())), CV_8UC3,
              cv::Scalar::all(255));
  for (std::size_t i = 0; i < panels.size(); ++i)
    drawPlotPanel(img(cv::Rect(int(i) * width, 0, width, height)), panels[i]);
  return img;
}

}  // namespace ps::app
