// Printable sheets: each sheet, rescaled as a camera or a scanner would see it, is read by the
// project's own detectors with the right id and the right physical size (pixels / dpi); the PNG
// carries its resolution and decodes to the same pixels; the PDF's structure is sound.
#include <gtest/gtest.h>

#include <zlib.h>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/input_error.hpp"
#include "tracking/charuco_calibration.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_sheet.hpp"

using namespace ps;

namespace {

// The sheet at `scale` of its size (area averaging), slightly blurred like a camera would.
cv::Mat rescaled(const cv::Mat& sheet, double scale) {
  cv::Mat small;
  cv::resize(sheet, small, {}, scale, scale, cv::INTER_AREA);
  cv::GaussianBlur(small, small, {0, 0}, 0.6);
  return small;
}

double meanEdge(const std::array<cv::Point2d, 4>& c) {
  double e = 0;
  for (int k = 0; k < 4; ++k) e += cv::norm(c[std::size_t(k)] - c[std::size_t((k + 1) % 4)]);
  return e / 4;
}

void expectMarkerSheetReads(const tracking::MarkerSheetSpec& spec, const tracking::Paper& paper) {
  const auto sheet = tracking::renderMarkerSheet(spec, paper, 300);
  SCOPED_TRACE(paper.name + " id " + std::to_string(spec.id));
  // Paper size at 300 dpi.
  EXPECT_EQ(sheet.image.cols, int(std::lround(paper.widthMm / 25.4 * 300)));
  EXPECT_EQ(sheet.image.rows, int(std::lround(paper.heightMm / 25.4 * 300)));
  // The marker's edge on the sheet is the size asked for, to the rounding of one pixel.
  EXPECT_NEAR(meanEdge(sheet.corners) * 25.4 / 300, spec.sizeMm, 25.4 / 300);
  const double scale = 0.25;  // 75 dpi
  tracking::DetectorConfig dc;
  dc.family = spec.family;
  dc.regions = false;
  dc.decimate = 1;
  std::vector<tracking::Backend> backends = {tracking::Backend::kAruco};
  if (tracking::familyInfo(spec.family).apriltag) backends.push_back(tracking::Backend::kAprilTag);
  for (const auto backend : backends) {
    dc.backend = backend;
    const auto found = tracking::makeDetector(dc)->detect(rescaled(sheet.image, scale));
    ASSERT_EQ(found.size(), 1u) << tracking::toString(backend) << ": one marker on the sheet";
    EXPECT_EQ(found[0].id, spec.id);
    std::array<cv::Point2d, 4> expected;
    for (int k = 0; k < 4; ++k)
      expected[std::size_t(k)] =
          (sheet.corners[std::size_t(k)] + cv::Point2d(0.5, 0.5)) * scale - cv::Point2d(0.5, 0.5);
    // AprilTag's edge refinement is exact to a fraction of a pixel; aruco's contour refinement
    // puts corners about half a pixel inside the marker (docs/TRACKING.md).
    const double tolerance = backend == tracking::Backend::kAprilTag ? 0.3 : 1.5;
    for (int k = 0; k < 4; ++k)
      EXPECT_LT(cv::norm(found[0].corners[std::size_t(k)] - expected[std::size_t(k)]), tolerance)
          << tracking::toString(backend) << " corner " << k;
    // Physical size from the detection: pixels at 75 dpi.
    EXPECT_NEAR(meanEdge(found[0].corners) / scale * 25.4 / 300, spec.sizeMm, 0.02 * spec.sizeMm)
        << tracking::toString(backend);
  }
}

std::string asString(const std::vector<std::uint8_t>& v) {
  return {v.begin(), v.end()};
}

}  // namespace

TEST(TrackingMarkers, PlanetAndToolSheetsAreDetectedWithTheirIdsAndSizes) {
  tracking::MarkerSheetSpec planet;  // tag36h11 id 0, 80 mm (SceneConfig's defaults)
  tracking::MarkerSheetSpec tool;
  tool.id = 1;
  tool.sizeMm = 50;
  tool.tool = true;
  for (const auto& paper : {tracking::paperA4(), tracking::paperLetter()}) {
    expectMarkerSheetReads(planet, paper);
    expectMarkerSheetReads(tool, paper);
  }
  tracking::MarkerSheetSpec aruco;
  aruco.family = "DICT_6X6_250";
  aruco.id = 17;
  aruco.sizeMm = 60;
  expectMarkerSheetReads(aruco, tracking::paperA4());
}

TEST(TrackingMarkers, BoardSheetReadsWithItsSquareSize) {
  const tracking::CharucoBoardSpec spec;
  for (const auto& paper : {tracking::paperA4(), tracking::paperLetter()}) {
    SCOPED_TRACE(paper.name);
    const auto sheet = tracking::renderCharucoSheet(spec, paper, 300);
    const double scale = 1.0 / 3;  // 100 dpi
    const auto board = spec.create();
    std::vector<cv::Point2f> corners;
    std::vector<int> ids;
    tracking::findCharucoCorners(rescaled(sheet.image, scale), board,
                                 cv::aruco::DetectorParameters::create(), corners, ids);
    ASSERT_EQ(int(ids.size()), spec.cornerCount());
    // Neighbouring corners (ids i and i+1 in a row) are one square apart: 30 mm at 100 dpi.
    const double squarePx = spec.squareLength * 1e3 / 25.4 * 300 * scale;
    const int perRow = spec.squaresX - 1;
    int pairs = 0;
    for (std::size_t a = 0; a < ids.size(); ++a)
      for (std::size_t b = 0; b < ids.size(); ++b)
        if (ids[b] == ids[a] + 1 && ids[a] % perRow != perRow - 1) {
          EXPECT_NEAR(cv::norm(corners[b] - corners[a]), squarePx, 0.25);
          ++pairs;
        }
    EXPECT_EQ(pairs, (spec.squaresX - 2) * (spec.squaresY - 1));
    // The board's outer size on the sheet.
    EXPECT_NEAR(cv::norm(sheet.corners[1] - sheet.corners[0]) * 25.4 / 300,
                spec.squaresX * spec.squareLength * 1e3, 25.4 / 300);
  }
}

TEST(TrackingMarkers, PngHasItsResolutionAndThePixels) {
  tracking::MarkerSheetSpec planet;
  const auto sheet = tracking::renderMarkerSheet(planet, tracking::paperA4(), 300);
  const auto png = tracking::encodeSheetPng(sheet.image, 300);
  const std::string s = asString(png);
  const auto at = s.find("pHYs");
  ASSERT_NE(at, std::string::npos);
  const auto u = [&](std::size_t i) { return std::uint8_t(s[i]); };
  const std::uint32_t ppm = (std::uint32_t(u(at + 4)) << 24) | (std::uint32_t(u(at + 5)) << 16) |
                            (std::uint32_t(u(at + 6)) << 8) | std::uint32_t(u(at + 7));
  EXPECT_EQ(ppm, 11811u);  // 300 dpi in pixels per metre
  const cv::Mat back = cv::imdecode(png, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(back.size(), sheet.image.size());
  EXPECT_EQ(cv::countNonZero(back != sheet.image), 0);
  EXPECT_LT(png.size(), 64u * 1024) << "a 1-bit sheet should compress well";
  cv::Mat grey = sheet.image.clone();
  grey.at<uchar>(0, 0) = 128;
  EXPECT_THROW(tracking::encodeSheetPng(grey, 300), std::invalid_argument);
}

// The sheet's image is its drawing to the pixel, at any resolution: black and white only, and
// every box (a marker's cells, the ChArUco board's squares, the scale bar) fills exactly the
// pixels between its edges' rounded positions: no blurred, grey or shifted cell edge.
TEST(TrackingMarkers, ImageHoldsEveryBoxOnItsRoundedPixels) {
  tracking::MarkerSheetSpec planet;
  tracking::MarkerSheetSpec aruco;
  aruco.family = "DICT_6X6_250";
  aruco.id = 17;
  aruco.sizeMm = 60;
  aruco.tool = true;
  for (const double dpi : {150.0, 203.0, 300.0}) {
    const tracking::Sheet sheets[] = {
        tracking::renderMarkerSheet(planet, tracking::paperA4(), dpi),
        tracking::renderMarkerSheet(aruco, tracking::paperLetter(), dpi),
        tracking::renderCharucoSheet(tracking::CharucoBoardSpec{}, tracking::paperA4(), dpi)};
    for (const auto& sheet : sheets) {
      SCOPED_TRACE(sheet.title + " at " + std::to_string(int(dpi)) + " dpi");
      const cv::Mat& img = sheet.image;
      ASSERT_EQ(img.type(), CV_8U);
      EXPECT_EQ(cv::countNonZero((img != 0) & (img != 255)), 0) << "only black and white";
      auto px = [&](double mm) { return int(std::floor(mm / 25.4 * dpi + 0.5)); };
      int boxes = 0;
      for (const auto& op : sheet.ops) {
        if (op.kind != tracking::SheetOp::Kind::kBox) continue;
        const cv::Rect r(cv::Point(px(op.x0), px(op.y0)), cv::Point(px(op.x1), px(op.y1)));
        if (r.empty()) continue;
        ASSERT_EQ(r & cv::Rect({}, img.size()), r);
        const int value = op.black ? 0 : 255;
        ASSERT_EQ(cv::countNonZero(img(r) != value), 0)
            << "box (" << op.x0 << ", " << op.y0 << ") - (" << op.x1 << ", " << op.y1
            << ") mm is not all " << value << " on pixels " << r;
        ++boxes;
      }
      EXPECT_GT(boxes, 50);
    }
  }
}

// The page's drawing: every FlateDecode stream of the PDF inflated and joined.
std::string inflatedStreams(const std::string& pdf) {
  std::string all;
  for (std::size_t at = pdf.find("stream\n"); at != std::string::npos;
       at = pdf.find("stream\n", at + 1)) {
    if (at >= 3 && pdf.compare(at - 3, 3, "end") == 0) continue;
    const std::size_t begin = at + 7, end = pdf.find("endstream", begin);
    if (end == std::string::npos) break;
    std::string out(64u << 20, '\0');
    uLongf size = uLongf(out.size());
    if (uncompress(reinterpret_cast<Bytef*>(out.data()), &size,
                   reinterpret_cast<const Bytef*>(pdf.data() + begin), uLong(end - begin)) == Z_OK)
      all += out.substr(0, size);
  }
  return all;
}

// The rectangles (x y w h) of the content's "x y w h re f" operators.
std::vector<cv::Vec4d> rectangles(const std::string& content) {
  std::vector<cv::Vec4d> out;
  for (std::size_t at = content.find(" re f"); at != std::string::npos;
       at = content.find(" re f", at + 1)) {
    std::size_t begin = at;
    for (int spaces = 0; begin > 0 && spaces < 4; --begin)
      if (content[begin - 1] == ' ' && ++spaces == 4) break;
    cv::Vec4d r;
    if (std::sscanf(content.c_str() + begin, "%lf %lf %lf %lf re", &r[0], &r[1], &r[2], &r[3]) == 4)
      out.push_back(r);
  }
  return out;
}

std::size_t occurrences(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

TEST(TrackingMarkers, PdfIsOnePageOfThePapersSizeWithTheMarkersAsVectors) {
  tracking::MarkerSheetSpec tool;
  tool.id = 1;
  tool.sizeMm = 50;
  tool.tool = true;
  for (const auto& paper : {tracking::paperA4(), tracking::paperLetter()}) {
    const auto sheet = tracking::renderMarkerSheet(tool, paper, 300);
    const std::string pdf = asString(tracking::encodeSheetPdf(sheet));
    EXPECT_EQ(pdf.rfind("%PDF-", 0), 0u);
    EXPECT_EQ(occurrences(pdf, "/Type /Page ") + occurrences(pdf, "/Type /Page\n"), 1u);
    const auto media = pdf.find("/MediaBox [ 0 0 ");
    ASSERT_NE(media, std::string::npos);
    double w = 0, h = 0;
    ASSERT_EQ(std::sscanf(pdf.c_str() + media, "/MediaBox [ 0 0 %lf %lf ]", &w, &h), 2);
    EXPECT_NEAR(w, paper.widthMm / 25.4 * 72, 1e-3) << paper.name;
    EXPECT_NEAR(h, paper.heightMm / 25.4 * 72, 1e-3) << paper.name;
    EXPECT_NE(pdf.find("/Title (" + sheet.title + ")"), std::string::npos);
    EXPECT_EQ(pdf.find("/Subtype /Image"), std::string::npos) << "the sheet must not be a raster";
    // Every box of the drawing is a rectangle in the page's content, and the marker's cells
    // are where the sheet put them (points = mm * 72 / 25.4; y down from the top after the
    // page's flip).
    const std::string content = inflatedStreams(pdf);
    std::size_t boxes = 0;
    for (const auto& op : sheet.ops) boxes += op.kind == tracking::SheetOp::Kind::kBox;
    EXPECT_EQ(occurrences(content, " re f"), boxes);
    const auto firstCell = std::find_if(sheet.ops.begin(), sheet.ops.end(), [](const auto& op) {
      return op.kind == tracking::SheetOp::Kind::kBox;
    });
    ASSERT_NE(firstCell, sheet.ops.end());
    const auto rects = rectangles(content);
    const double k = 72 / 25.4;
    const bool placed = std::any_of(rects.begin(), rects.end(), [&](const cv::Vec4d& r) {
      return std::abs(r[0] - firstCell->x0 * k) < 0.01 &&
             std::abs(r[1] - firstCell->y0 * k) < 0.01 &&
             std::abs(r[2] - (firstCell->x1 - firstCell->x0) * k) < 0.01 &&
             std::abs(r[3] - (firstCell->y1 - firstCell->y0) * k) < 0.01;
    });
    EXPECT_TRUE(placed) << "no rectangle at the first cell (" << firstCell->x0 << ", "
                        << firstCell->y0 << ") mm";
    // The text is text (a font), not pixels.
    EXPECT_NE(content.find("(PlanetSculpt tool marker)Tj"), std::string::npos);
  }
}

TEST(TrackingMarkers, BadSheetsAreRefused) {
  tracking::MarkerSheetSpec bad;
  bad.id = 100000;
  EXPECT_THROW(tracking::renderMarkerSheet(bad, tracking::paperA4()), core::InputError);
  tracking::MarkerSheetSpec huge;
  huge.sizeMm = 250;
  EXPECT_THROW(tracking::renderMarkerSheet(huge, tracking::paperLetter()), core::InputError);
  tracking::CharucoBoardSpec big;
  big.squareLength = 0.05;
  EXPECT_THROW(tracking::renderCharucoSheet(big, tracking::paperA4()), core::InputError);
  EXPECT_THROW(tracking::paperFromString("a3"), core::InputError);
}
