#pragma once
// Print-ready sheets (what `planetsculpt markers` writes): the planet marker, the tool marker, the
// planet board, the tool cube's net and the ChArUco calibration board, each on an A4 or US
// Letter page at a given resolution (300 dpi by default), black and white only, with the
// physical size, family and ids printed on the sheet and a 100 mm scale bar to check that it
// was printed at 100 %.
//
// A sheet is drawn once, as steps in millimetres (SheetOp), and one cairo function paints the
// steps onto any surface (sheet_files.cpp): an image surface at the sheet's dpi gives its pixels
// (written as a 1-bit PNG with its resolution in a pHYs chunk, libpng), a PDF surface the
// one-page vector PDF at their exact sizes, so that the markers' cells print sharp at any
// printer resolution.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "tracking/charuco_calibration.hpp"
#include "tracking/marker_layout.hpp"

namespace ps::tracking {

struct Paper {
  std::string name;  // "A4", "US Letter"
  std::string tag;   // "a4", "letter" (file names)
  double widthMm = 0, heightMm = 0;
};
Paper paperA4();
Paper paperLetter();
Paper paperFromString(const std::string& s);  // "a4" | "letter"; core::InputError

struct MarkerSheetSpec {
  std::string family = "tag36h11";
  int id = 0;
  double sizeMm = 80;                      // the marker's edge: outer edge of the black border
  bool tool = false;                       // tool marker: draw the stick and the tip
  Eigen::Vector3d tipOffsetMm{0, -80, 0};  // tool tip in the marker frame (x right, y up, z out)
  double planetRadiusMm = 60;              // planet marker: the planet's radius (label only)
};

// One drawing step of a sheet, in millimetres from the page's top-left corner: what the PDF draws
// as vectors and the sheet's image holds rasterised at its dpi.
struct SheetOp {
  enum class Kind { kBox, kLine, kText };
  Kind kind = Kind::kBox;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // a box's corners, a line's ends; text: its anchor
  bool black = true;                      // a box's colour (white boxes cover black ones)
  double size = 0;                        // a line's width, the text's capital height
  std::string text;
  bool centre = false, bold = false;  // text centred on x0; bold
};

struct Sheet {
  cv::Mat image;             // CV_8U, 0 or 255 only, portrait, paper size at `dpi`
  std::vector<SheetOp> ops;  // the same drawing, in millimetres, in painting order
  double dpi = 300;
  Paper paper;
  std::string title;
  // Where the marker's edge corners (TL, TR, BR, BL of the canonical image) are, in OpenCV's
  // pixel convention (marker sheets; for the board, its outer corners TL, TR, BR, BL).
  std::array<cv::Point2d, 4> corners{};
  // Layout sheets (the planet board, the tool cube's net): every marker's edge corners, TL, TR,
  // BR, BL of its canonical image, by id.
  std::vector<std::pair<int, std::array<cv::Point2d, 4>>> markers;
};

// Throws core::InputError for a bad family, id or size, or a marker that does not fit the page.
Sheet renderMarkerSheet(const MarkerSheetSpec& spec, const Paper& paper, double dpi = 300);
Sheet renderCharucoSheet(const CharucoBoardSpec& board, const Paper& paper, double dpi = 300);

// The planet board (marker_layout.hpp) at its exact size with the planet's place marked. Throws
// core::InputError naming the layout when its markers are not upright in its z = 0 plane (what a
// flat sheet can hold) or the board does not fit the page.
Sheet renderBoardSheet(const MarkerLayout& board, const Paper& paper, double dpi = 300);
// The tool cube's net (a cross of six faces: the layout's markers on their faces, the stick's
// face marked) so that, cut out and folded with the printed side out, each marker sits where
// the layout says. InputError naming the layout when it is not a cube of that convention
// (markers/tool-cube.json: face frames as docs/TRACKING.md shows) or does not fit the page.
Sheet renderCubeNetSheet(const MarkerLayout& cube, const Paper& paper, double dpi = 300);

// The steps painted by cairo onto an image surface of `size` pixels at `dpi`: 0 (black) or 255
// only. Boxes have their edges on the rounded pixel boundaries (a marker's cells exact to the
// pixel, no antialiasing anywhere); a line is at least one pixel wide.
cv::Mat rasterizeSheet(const std::vector<SheetOp>& ops, cv::Size size, double dpi);

// A bilevel image (0 or 255) as a 1-bit PNG with a pHYs chunk saying `dpi`; std::invalid_argument
// for other values.
std::vector<std::uint8_t> encodeSheetPng(const cv::Mat& image, double dpi);
// The sheet's drawing steps as a one-page vector PDF of its paper's size, its title in the
// document information.
std::vector<std::uint8_t> encodeSheetPdf(const Sheet& sheet);

}  // namespace ps::tracking
