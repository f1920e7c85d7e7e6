// Printable sheets of rigid marker sets (marker_sheet.hpp): the planet board at its exact size
// and the tool cube's net.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/marker_sheet.hpp"
#include "tracking/sheet_canvas.hpp"

namespace ps::tracking {

using namespace sheet_detail;

namespace {

void checkResolution(double dpi) {
  if (!(dpi >= 72 && dpi <= 1200)) throw core::InputError("sheet resolution must be 72..1200 dpi");
}

// Paints marker `id`'s cells with its edge's top-left corner at (x, y) mm on the page, turned
// by 180 degrees when `turned`; returns its edge corners (TL, TR, BR, BL of the canonical image).
std::array<cv::Point2d, 4> paintMarker(Canvas& c, const std::string& family, int id, double x,
                                       double y, double edgeMm, bool turned) {
  const FamilyInfo info = familyInfo(family);
  const double cellMm = edgeMm / info.edgeCells;
  cv::Mat cells = markerCells(family, id);
  if (turned) cv::rotate(cells, cells, cv::ROTATE_180);
  const int lead = turned ? info.totalCells - info.edgeOffset - info.edgeCells : info.edgeOffset;
  paintCells(c, cells, x - lead * cellMm, y - lead * cellMm, cellMm);
  const auto box = cornersPx(c, x, y, x + edgeMm, y + edgeMm);  // page TL, TR, BR, BL
  if (!turned) return box;
  return {box[2], box[3], box[0], box[1]};
}

// A fold line: dashes with a gap at both ends, so that it touches neither the cut outline nor
// another fold. Solid lines round a face would close a square one quiet zone outside its marker,
// which OpenCV's aruco detector takes for a candidate "too close" to the marker
// (DetectorParameters::minMarkerDistanceRate: mean corner distance under 5 % of the perimeter;
// a one-cell quiet zone is under that from 8 cells across, DICT_6X6 and up) and keeps the
// larger of the two: the outline, which decodes to nothing, and the marker is lost.
void foldLine(Canvas& c, double x0, double y0, double x1, double y1) {
  constexpr double kDash = 3, kGap = 2, kWidth = 0.2;
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int dashes = int(std::floor((len - kGap) / (kDash + kGap)));
  const double first = (len - dashes * kDash - (dashes - 1) * kGap) / 2;
  for (int k = 0; k < dashes; ++k) {
    const double a = (first + k * (kDash + kGap)) / len, b = a + kDash / len;
    c.line(x0 + a * (x1 - x0), y0 + a * (y1 - y0), x0 + b * (x1 - x0), y0 + b * (y1 - y0), kWidth);
  }
}

// A face of the cube's net: its outward normal and x axis in the cube's frame, its place in the
// net (column, row in faces) and whether its marker is printed turned by 180 degrees.
struct Slot {
  Eigen::Vector3d normal, x;
  int col, row;
  bool turned;
};

// The net's cut lines (solid, where no face is beyond an edge) and fold lines (dashed, between
// two faces, each drawn once).
void netLines(Canvas& c, const Slot (&slots)[6], double left, double top, double faceMm) {
  auto inNet = [&](int col, int row) {
    return std::any_of(std::begin(slots), std::end(slots),
                       [&](const Slot& o) { return o.col == col && o.row == row; });
  };
  for (const Slot& s : slots) {
    const double fx = left + s.col * faceMm, fy = top + s.row * faceMm;
    const struct {
      int dc, dr;
      double x0, y0, x1, y1;
    } edges[] = {{0, -1, fx, fy, fx + faceMm, fy},
                 {0, 1, fx, fy + faceMm, fx + faceMm, fy + faceMm},
                 {-1, 0, fx, fy, fx, fy + faceMm},
                 {1, 0, fx + faceMm, fy, fx + faceMm, fy + faceMm}};
    for (const auto& e : edges) {
      if (!inNet(s.col + e.dc, s.row + e.dr))
        c.line(e.x0, e.y0, e.x1, e.y1, 0.2);
      else if (e.dc + e.dr > 0)  // the face below or right of it does not draw it again
        foldLine(c, e.x0, e.y0, e.x1, e.y1);
    }
  }
}

void crosshair(Canvas& c, double x, double y, double armMm) {
  c.line(x - armMm, y, x + armMm, y, 0.25);
  c.line(x, y - armMm, x, y + armMm, 0.25);
}

}  // namespace

Sheet renderBoardSheet(const MarkerLayout& board, const Paper& paper, double dpi) {
  checkResolution(dpi);
  auto refuse = [&](const std::string& why) {
    throw core::InputError(board.source + ": cannot print as a board: " + why);
  };
  if (!board.planetCentre) refuse("it has no planet_centre");
  const FamilyInfo info = familyInfo(board.family);
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (const auto& m : board.markers) {
    const Pose p = m.inBody();
    if ((p.R - Eigen::Matrix3d::Identity()).norm() > 1e-6 || std::abs(p.t.z()) > 1e-9)
      refuse("marker " + std::to_string(m.id) +
             " is not upright in the z = 0 plane (x along the sheet's width, y up the sheet)");
    const double quiet = m.edge() * info.edgeOffset / info.edgeCells;
    x0 = std::min(x0, m.corners[0].x() - quiet), x1 = std::max(x1, m.corners[1].x() + quiet);
    y0 = std::min(y0, m.corners[2].y() - quiet), y1 = std::max(y1, m.corners[0].y() + quiet);
  }
  Canvas c(paper, dpi);
  const double W = c.widthMm(), widthMm = 1e3 * (x1 - x0), heightMm = 1e3 * (y1 - y0);
  if (widthMm > W - 16 || heightMm > c.heightMm() - 75)
    refuse(mm(widthMm) + " x " + mm(heightMm) + " mm does not fit on " + paper.name);
  Sheet sheet;
  sheet.dpi = dpi;
  sheet.paper = paper;
  sheet.title = "PlanetSculpt planet board";
  c.text(sheet.title, W / 2, 20, 6, true, true);
  // Board metres -> page millimetres: centred across, its top 30 mm down; y up the sheet.
  const double top = 32, ox = W / 2 - 1e3 * 0.5 * (x0 + x1), oy = top + 1e3 * y1;
  auto page = [&](const Eigen::Vector3d& b) {
    return cv::Point2d(ox + 1e3 * b.x(), oy - 1e3 * b.y());
  };
  std::string ids;
  for (const auto& m : board.markers) {
    const cv::Point2d tl = page(m.corners[0]);
    sheet.markers.emplace_back(
        m.id, paintMarker(c, board.family, m.id, tl.x, tl.y, 1e3 * m.edge(), false));
    ids += (ids.empty() ? "" : " ") + std::to_string(m.id);
  }
  // The planet's place: ticks in line with its centre, outside the markers (a mark on a marker
  // would change its cells).
  const cv::Point2d centre = page(*board.planetCentre);
  const double left = ox + 1e3 * x0, right = ox + 1e3 * x1, bottom = top + heightMm;
  c.line(left - 6, centre.y, left - 1, centre.y, 0.3);
  c.line(right + 1, centre.y, right + 6, centre.y, 0.3);
  c.line(centre.x, top - 6, centre.x, top - 1, 0.3);
  c.line(centre.x, bottom + 1, centre.x, bottom + 6, 0.3);
  double y = bottom + 12;
  c.text(board.family + "  ids " + ids + "  |  " + mm(1e3 * board.markers.front().edge()) +
             " mm markers",
         W / 2, y, 2.8, true, true);
  y += 5;
  c.text("The planet stands where the four ticks' lines cross. Glue flat on stiff card.", W / 2, y,
         2.4, true);
  y += 4.5;
  c.text("A hand or the tool over some of the markers is fine.  Layout: " +
             std::filesystem::path(board.source).filename().string(),
         W / 2, y, 2.4, true);
  return finish(c, std::move(sheet), c.heightMm() - 23);
}

Sheet renderCubeNetSheet(const MarkerLayout& cube, const Paper& paper, double dpi) {
  checkResolution(dpi);
  auto refuse = [&](const std::string& why) {
    throw core::InputError(cube.source + ": cannot print as a cube net: " + why);
  };
  if (cube.markers.empty()) refuse("no markers");
  const FamilyInfo info = familyInfo(cube.family);
  const double edge = cube.markers.front().edge();
  const double half = edge * info.totalCells / info.edgeCells / 2;  // the face, quiet zone included
  // The net, as a cross (column, row in faces): top (+y) over front (+z) over bottom (-y) over
  // back (-z), -x left and +x right of the front. Folding it printed side out puts each face's
  // (x, y) where these frames say; the back, reached over the bottom, is printed turned.
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  const Slot slots[] = {{Y, X, 1, 0, false},  {Z, X, 1, 1, false},  {-Y, X, 1, 2, false},
                        {-Z, -X, 1, 3, true}, {-X, Z, 0, 1, false}, {X, -Z, 2, 1, false}};
  std::vector<const LayoutMarker*> onSlot(6, nullptr);
  for (const auto& m : cube.markers) {
    const Pose p = m.inBody();
    if (std::abs(m.edge() - edge) > 1e-4) refuse("its markers differ in size");
    bool placed = false;
    for (std::size_t s = 0; s < 6; ++s)
      if ((p.R.col(2) - slots[s].normal).norm() < 1e-6 && (p.R.col(0) - slots[s].x).norm() < 1e-6 &&
          (p.t - half * slots[s].normal).norm() < 1e-5) {
        if (onSlot[s]) refuse("two markers on one face");
        onSlot[s] = &m;
        placed = true;
      }
    if (!placed)
      refuse("marker " + std::to_string(m.id) +
             " is not on a face of a cube centred at the origin whose faces just hold the markers");
  }
  if (onSlot[2]) refuse("the bottom (-y) face holds the stick, not a marker");
  Canvas c(paper, dpi);
  const double W = c.widthMm(), faceMm = 2e3 * half;
  if (3 * faceMm > W - 16 || 4 * faceMm > c.heightMm() - 70)
    refuse("a " + mm(faceMm) + " mm cube's net does not fit on " + paper.name);
  Sheet sheet;
  sheet.dpi = dpi;
  sheet.paper = paper;
  sheet.title = "PlanetSculpt tool cube";
  c.text(sheet.title, W / 2, 20, 6, true, true);
  const double top = 28, left = W / 2 - 1.5 * faceMm;
  for (std::size_t s = 0; s < 6; ++s) {
    const double fx = left + slots[s].col * faceMm, fy = top + slots[s].row * faceMm;
    if (onSlot[s]) {
      const double e = 1e3 * onSlot[s]->edge();
      const double gap = (faceMm - e) / 2;
      sheet.markers.emplace_back(onSlot[s]->id, paintMarker(c, cube.family, onSlot[s]->id, fx + gap,
                                                            fy + gap, e, slots[s].turned));
    } else if (slots[s].normal == -Y) {
      crosshair(c, fx + faceMm / 2, fy + faceMm / 2, 4);
      c.text("stick", fx + faceMm / 2, fy + faceMm / 2 + 10, 2.6, true);
    }
  }
  netLines(c, slots, left, top, faceMm);  // over the faces' white quiet zones, not under them
  double y = top + 4 * faceMm + 8;
  std::string ids;
  for (const auto& m : cube.markers) ids += (ids.empty() ? "" : " ") + std::to_string(m.id);
  c.text(cube.family + "  ids " + ids + "  |  " + mm(faceMm) + " mm faces  |  tip " +
             mm(1e3 * cube.tip.value_or(Eigen::Vector3d::Zero()).norm()) + " mm below the centre",
         W / 2, y, 2.6, true, true);
  y += 5;
  c.text("Glue on card, cut along the solid lines, fold along the dashed ones printed side out,",
         W / 2, y, 2.4, true);
  y += 4.5;
  c.text("tape the edges; the stick goes into the cross.", W / 2, y, 2.4, true);
  return finish(c, std::move(sheet), c.heightMm() - 23);
}

}  // namespace ps::tracking
