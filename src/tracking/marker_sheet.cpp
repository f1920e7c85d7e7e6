#include "tracking/marker_sheet.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <opencv2/aruco.hpp>
#include <sstream>
#include <stdexcept>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/sheet_canvas.hpp"

namespace ps::tracking {

using namespace sheet_detail;

namespace {

// The ChArUco board's squares and markers as boxes with its top-left corner at (x0, y0) mm (the
// boxes renderCharucoBoard fills).
void charucoSteps(Canvas& c, const CharucoBoardSpec& spec, double x0, double y0) {
  const auto board = spec.create();
  const double sq = spec.squareLength * 1e3;
  for (int r = 0; r < spec.squaresY; ++r)
    for (int k = 0; k < spec.squaresX; ++k)
      if (r % 2 == k % 2) c.box(x0 + k * sq, y0 + r * sq, x0 + (k + 1) * sq, y0 + (r + 1) * sq);
  const int cells = board->dictionary->markerSize + 2;
  const double cell = spec.markerLength * 1e3 / cells;
  for (std::size_t i = 0; i < board->ids.size(); ++i) {
    cv::Mat bits;
    cv::aruco::drawMarker(board->dictionary, board->ids[i], cells, bits, 1);
    const double mx = x0 + board->objPoints[i][0].x * 1e3, my = y0 + board->objPoints[i][0].y * 1e3;
    for (int a = 0; a < cells; ++a)
      for (int b = 0; b < cells; ++b)
        c.box(mx + b * cell, my + a * cell, mx + (b + 1) * cell, my + (a + 1) * cell,
              bits.at<uchar>(a, b) ? 255 : 0);
  }
}

}  // namespace

Paper paperA4() {
  return {"A4", "a4", 210.0, 297.0};
}
Paper paperLetter() {
  return {"US Letter", "letter", 215.9, 279.4};
}
Paper paperFromString(const std::string& s) {
  if (s == "a4" || s == "A4") return paperA4();
  if (s == "letter" || s == "us-letter") return paperLetter();
  throw core::InputError("paper '" + s + "' is not one of a4, letter");
}

Sheet renderMarkerSheet(const MarkerSheetSpec& spec, const Paper& paper, double dpi) {
  if (!(dpi >= 72 && dpi <= 1200)) throw core::InputError("sheet resolution must be 72..1200 dpi");
  if (!(spec.sizeMm >= 10)) throw core::InputError("marker size " + mm(spec.sizeMm) + " mm < 10");
  const FamilyInfo info = familyInfo(spec.family);
  const cv::Mat cells = markerCells(spec.family, spec.id);  // InputError for a bad id
  const double cellMm = spec.sizeMm / info.edgeCells;
  const double totalMm = cellMm * info.totalCells;
  Canvas c(paper, dpi);
  const double W = c.widthMm();
  if (totalMm > W - 30 || totalMm > c.heightMm() - 120)
    throw core::InputError("a " + mm(spec.sizeMm) + " mm marker does not fit on " + paper.name);
  Sheet sheet;
  sheet.dpi = dpi;
  sheet.paper = paper;
  sheet.title = std::string("PlanetSculpt ") + (spec.tool ? "tool" : "planet") + " marker";
  c.text(sheet.title, W / 2, 22, 6, true, true);
  const double top = 32;
  const double x0 = (W - totalMm) / 2;
  paintCells(c, cells, x0, top, cellMm);
  const double ex0 = x0 + info.edgeOffset * cellMm, ey0 = top + info.edgeOffset * cellMm;
  sheet.corners = cornersPx(c, ex0, ey0, ex0 + spec.sizeMm, ey0 + spec.sizeMm);
  const double cx = ex0 + spec.sizeMm / 2, cy = ey0 + spec.sizeMm / 2;
  const double quiet = info.edgeOffset * cellMm;  // the white ring outside the edge
  double y = top + totalMm + 2;

  if (spec.tool) {
    // The stick: a dashed line from below the marker's white ring to the tip, drawn where the
    // tip lies in the marker's plane (x right, y up on the paper).
    const double tx = cx + spec.tipOffsetMm.x(), ty = cy - spec.tipOffsetMm.y();
    const double startY = ey0 + spec.sizeMm + quiet + 3;
    if (ty > startY + 5 && ty < c.heightMm() - 60) {
      const double len = ty - startY;
      for (double d = 0; d < len; d += 6)
        c.line(cx + (tx - cx) * d / len, startY + (ty - startY) * d / len,
               cx + (tx - cx) * std::min(len, d + 3.5) / len,
               startY + (ty - startY) * std::min(len, d + 3.5) / len, 0.5);
      c.line(tx - 4, ty, tx + 4, ty, 0.4);
      c.line(tx, ty - 4, tx, ty + 4, 0.4);
      c.text("tip", tx + 5, ty + 1.2, 3);
      y = ty + 8;
    }
  }
  c.text(spec.family + "   id " + std::to_string(spec.id), W / 2, y + 8, 5, true, true);
  y += 16;
  c.text("Marker edge " + mm(spec.sizeMm) + " mm (outer edge of the black border)", W / 2, y, 3.2,
         true);
  y += 6;
  std::vector<std::string> notes;
  if (spec.tool) {
    const auto& t = spec.tipOffsetMm;
    notes = {
        "Tool tip offset (" + mm(t.x()) + ", " + mm(t.y()) + ", " + mm(t.z()) +
            ") mm from the marker centre,",
        "in the marker frame: x right, y up, z out of the paper (replay --tip in metres).",
        "Glue the marker flat on card, then to a stick that runs along the dashed line;",
        "the stick's tip must be at the cross. Keep the white ring around the marker clear.",
    };
  } else {
    notes = {
        "The planet (radius " + mm(spec.planetRadiusMm) +
            " mm) sits on this marker: its centre is " + mm(spec.planetRadiusMm) + " mm",
        "above the marker centre, its north pole along the marker's z (out of the paper).",
        "Glue it flat on stiff card or the table. Keep the white ring around the marker clear.",
    };
  }
  notes.push_back("Check it: planetsculpt detect PHOTO --family " + spec.family +
                  " --marker-size " + mm(spec.sizeMm / 1000));
  for (const auto& n : notes) {
    c.text(n, 18, y, 2.6);
    y += 4.6;
  }
  return finish(c, std::move(sheet), c.heightMm() - 32);
}

Sheet renderCharucoSheet(const CharucoBoardSpec& board, const Paper& paper, double dpi) {
  if (!(dpi >= 72 && dpi <= 1200)) throw core::InputError("sheet resolution must be 72..1200 dpi");
  board.validate();
  Canvas c(paper, dpi);
  const double W = c.widthMm();
  const double bw = board.squaresX * board.squareLength * 1e3;
  const double bh = board.squaresY * board.squareLength * 1e3;
  if (bw > W - 16 || bh > c.heightMm() - 62)
    throw core::InputError("the board (" + mm(bw) + " x " + mm(bh) + " mm) does not fit on " +
                           paper.name);
  Sheet sheet;
  sheet.dpi = dpi;
  sheet.paper = paper;
  sheet.title = "PlanetSculpt ChArUco calibration board";
  c.text(sheet.title, W / 2, 14, 4.5, true, true);
  const double top = 19, x0 = (W - bw) / 2;
  // The board's top-left corner on a pixel of the image: its squares are then as
  // renderCharucoBoard draws them at this resolution.
  const double bx = c.ipx(x0) * 25.4 / dpi, by = c.ipx(top) * 25.4 / dpi;
  charucoSteps(c, board, bx, by);
  sheet.corners = cornersPx(c, bx, by, bx + bw, by + bh);
  double y = top + bh + 6;
  c.text(board.describe(), W / 2, y, 3.4, true, true);
  y += 5.5;
  c.text("planetsculpt calibrate VIDEO --squares " + std::to_string(board.squaresX) + "x" +
             std::to_string(board.squaresY) + " --square-mm " + mm(board.squareLength * 1e3) +
             " --marker-mm " + mm(board.markerLength * 1e3) + " --dictionary " + board.dictionary,
         W / 2, y, 2.4, true);
  y += 4.5;
  c.text("Glue flat on stiff card. Film it from many angles, filling the image's corners.", W / 2,
         y, 2.4, true);
  return finish(c, std::move(sheet), c.heightMm() - 23);
}

}  // namespace ps::tracking
