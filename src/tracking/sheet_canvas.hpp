#pragma once
// Drawing printable sheets in millimetres (marker_sheet.cpp: single markers and the ChArUco
// board; layout_sheet.cpp: the planet board and the tool cube's net). Not part of the library's
// interface.
#include <algorithm>
#include <array>
#include <cmath>
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

// Drawing in millimetres on a page at `dpi` (origin at the page's top-left corner), recorded as
// steps: sheet_files.cpp draws them through cairo onto the sheet's image and into its PDF.
struct Canvas {
  int cols, rows;  // the page in pixels at `dpi`
  double dpi;
  std::vector<SheetOp> ops;

  Canvas(const Paper& paper, double d)
      : cols(int(std::lround(paper.widthMm / 25.4 * d))),
        rows(int(std::lround(paper.heightMm / 25.4 * d))),
        dpi(d) {}
  double px(double v) const { return v / 25.4 * dpi; }
  int ipx(double v) const { return int(std::lround(px(v))); }
  double widthMm() const { return cols * 25.4 / dpi; }
  double heightMm() const { return rows * 25.4 / dpi; }

  // Box from (x0, y0) to (x1, y1) mm (in the image, its edges at the rounded pixel boundaries).
  void box(double x0, double y0, double x1, double y1, uchar v = 0) {
    ops.push_back({SheetOp::Kind::kBox, x0, y0, x1, y1, v == 0, 0, {}, false, false});
  }
  void line(double x0, double y0, double x1, double y1, double widthMm) {
    ops.push_back({SheetOp::Kind::kLine, x0, y0, x1, y1, true, widthMm, {}, false, false});
  }
  // Text with its baseline at y and capital letters `heightMm` tall; centred on x or from x.
  void text(const std::string& s, double x, double y, double heightMm, bool centre = false,
            bool bold = false) {
    ops.push_back({SheetOp::Kind::kText, x, y, x, y, true, heightMm, s, centre, bold});
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
  sheet.ops = std::move(c.ops);
  sheet.image = rasterizeSheet(sheet.ops, {c.cols, c.rows}, c.dpi);
  return sheet;
}

}  // namespace ps::tracking::sheet_detail
