#pragma once
// Drawing printable sheets in millimetres (marker_sheet.cpp: single markers and the ChArUco
// board; layout_sheet.cpp: the planet board and the tool cube's net). Not part of the library's
// interface.
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tracking/marker_sheet.hpp"

namespace ps::tracking::sheet_detail {

inline std::string mm(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// Drawing in millimetres on a page at `dpi` (origin at the page's top-left corner): into the
// raster image, and recorded as steps for the vector PDF.
struct Canvas {
  cv::Mat img;
  double dpi;
  std::vector<SheetOp> ops;

  Canvas(const Paper& paper, double d)
      : img(int(std::lround(paper.heightMm / 25.4 * d)), int(std::lround(paper.widthMm / 25.4 * d)),
            CV_8U, cv::Scalar(255)),
        dpi(d) {}
  double px(double v) const { return v / 25.4 * dpi; }
  int ipx(double v) const { return int(std::lround(px(v))); }
  double widthMm() const { return img.cols * 25.4 / dpi; }
  double heightMm() const { return img.rows * 25.4 / dpi; }

  // Box from (x0, y0) to (x1, y1) mm, edges at the rounded pixel boundaries.
  void box(double x0, double y0, double x1, double y1, uchar v = 0) {
    vectorBox(x0, y0, x1, y1, v);
    const int ix0 = ipx(x0), iy0 = ipx(y0), ix1 = ipx(x1), iy1 = ipx(y1);
    const cv::Rect r = cv::Rect(ix0, iy0, ix1 - ix0, iy1 - iy0) & cv::Rect({}, img.size());
    if (r.area() > 0) img(r).setTo(v);
  }
  // A box in the PDF only (where the raster comes from another renderer at this page's pixels).
  void vectorBox(double x0, double y0, double x1, double y1, uchar v = 0) {
    ops.push_back({SheetOp::Kind::kBox, x0, y0, x1, y1, v == 0, 0, {}, false, false});
  }
  void line(double x0, double y0, double x1, double y1, double widthMm) {
    ops.push_back({SheetOp::Kind::kLine, x0, y0, x1, y1, true, widthMm, {}, false, false});
    cv::line(img, {ipx(x0), ipx(y0)}, {ipx(x1), ipx(y1)}, cv::Scalar(0), std::max(1, ipx(widthMm)),
             cv::LINE_8);
  }
  // Text with its baseline at y and capital letters `heightMm` tall; centred on x or from x.
  void text(const std::string& s, double x, double y, double heightMm, bool centre = false,
            bool bold = false) {
    ops.push_back({SheetOp::Kind::kText, x, y, x, y, true, heightMm, s, centre, bold});
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    const double scale = px(heightMm) / 22.0;  // capital height of this font at scale 1
    const int thick = std::max(1, int(std::lround(scale * (bold ? 2.6 : 1.5))));
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, font, scale, thick, &base);
    const int ix = centre ? ipx(x) - sz.width / 2 : ipx(x);
    cv::putText(img, s, {ix, ipx(y)}, font, scale, cv::Scalar(0), thick, cv::LINE_8);
  }
  double textWidthMm(const std::string& s, double heightMm) const {
    const double scale = px(heightMm) / 22.0;
    int base = 0;
    const int thick = std::max(1, int(std::lround(scale * 1.5)));
    return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, thick, &base).width * 25.4 / dpi;
  }

  // 100 mm scale bar with centimetre ticks, centred on the page, its top at y.
  void scaleBar(double y) {
    const double x0 = (widthMm() - 100) / 2;
    text("This bar must measure 100 mm. If not, print again at 100 % (actual size, not 'fit').",
         widthMm() / 2, y - 3, 2.6, true);
    box(x0, y, x0 + 100, y + 1.5);
    for (int k = 0; k <= 10; ++k) {
      const double x = x0 + 10 * k;
      const double len = k % 5 == 0 ? 5 : 3;
      box(x - 0.15, y, x + 0.15, y + len);
    }
    text("0", x0, y + 9, 2.6, true);
    text("50 mm", x0 + 50, y + 9, 2.6, true);
    text("100 mm", x0 + 100, y + 9, 2.6, true);
  }
};

// Paints a cell image (one byte per cell, 0 black) with its top-left corner at (x, y) mm and
// cells `cellMm` wide, every cell edge at its rounded exact pixel position.
inline void paintCells(Canvas& c, const cv::Mat& cells, double x, double y, double cellMm) {
  for (int r = 0; r < cells.rows; ++r)
    for (int k = 0; k < cells.cols; ++k)
      c.box(x + k * cellMm, y + r * cellMm, x + (k + 1) * cellMm, y + (r + 1) * cellMm,
            cells.at<uchar>(r, k) ? 255 : 0);
}

inline std::array<cv::Point2d, 4> cornersPx(const Canvas& c, double x0, double y0, double x1,
                                            double y1) {
  // A pixel-boundary position e (pixels) is e - 0.5 in OpenCV's convention.
  auto p = [&](double x, double y) {
    return cv::Point2d(std::lround(c.px(x)) - 0.5, std::lround(c.px(y)) - 0.5);
  };
  return {p(x0, y0), p(x1, y0), p(x1, y1), p(x0, y1)};
}

inline void footer(Canvas& c, const Paper& paper, double dpi) {
  c.text("PlanetSculpt  |  " + paper.name + " " + mm(paper.widthMm) + " x " + mm(paper.heightMm) +
             " mm  |  " + mm(dpi) + " dpi  |  docs/TRACKING.md",
         c.widthMm() / 2, c.heightMm() - 8, 2.2, true);
}

// The sheet's last lines (the scale bar with its top at `scaleBarY`, the footer) and the drawing
// into `sheet`.
inline Sheet finish(Canvas& c, Sheet sheet, double scaleBarY) {
  c.scaleBar(scaleBarY);
  footer(c, sheet.paper, c.dpi);
  sheet.image = c.img;
  sheet.ops = std::move(c.ops);
  return sheet;
}

}  // namespace ps::tracking::sheet_detail
