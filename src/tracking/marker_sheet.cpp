#include "tracking/marker_sheet.hpp"

#include <zlib.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

#include "core/input_error.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/sheet_canvas.hpp"

namespace ps::tracking {

using namespace sheet_detail;

namespace {

// --- PNG and PDF -----------------------------------------------------------------------------

void put32(std::vector<std::uint8_t>& v, std::uint32_t x) {
  for (int s = 24; s >= 0; s -= 8) v.push_back(std::uint8_t(x >> s));
}
std::uint32_t get32(const std::uint8_t* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         std::uint32_t(p[3]);
}

void checkBilevel(const cv::Mat& image) {
  if (image.type() != CV_8U || image.empty())
    throw std::invalid_argument("sheet images are 8-bit grey");
  cv::Mat other = (image != 0) & (image != 255);
  if (cv::countNonZero(other) > 0) throw std::invalid_argument("sheet images are 0 or 255 only");
}

struct PngParts {
  int width = 0, height = 0, bitDepth = 0, colourType = 0, interlace = 0;
  std::vector<std::uint8_t> idat;  // the zlib stream, all IDAT chunks joined
};

PngParts parsePng(const std::vector<std::uint8_t>& png) {
  static const std::uint8_t sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
  if (png.size() < 8 || std::memcmp(png.data(), sig, 8) != 0)
    throw std::runtime_error("not a PNG stream");
  PngParts parts;
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::uint32_t len = get32(&png[at]);
    const std::string type(reinterpret_cast<const char*>(&png[at + 4]), 4);
    if (at + 12 + len > png.size()) throw std::runtime_error("truncated PNG chunk " + type);
    const std::uint8_t* d = &png[at + 8];
    if (type == "IHDR") {
      parts.width = int(get32(d));
      parts.height = int(get32(d + 4));
      parts.bitDepth = d[8];
      parts.colourType = d[9];
      parts.interlace = d[12];
    } else if (type == "IDAT") {
      parts.idat.insert(parts.idat.end(), d, d + len);
    }
    at += 12 + len;
  }
  return parts;
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
  c.scaleBar(c.heightMm() - 32);
  footer(c, paper, dpi);
  sheet.image = c.img;
  return sheet;
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
  // The board's own renderer at this page's resolution, placed at the rounded pixel of its
  // top-left corner (its squares are then on this page's rounded grid too).
  const cv::Mat img = renderCharucoBoard(board, dpi / 0.0254, 0);
  const cv::Rect r(c.ipx(x0), c.ipx(top), img.cols, img.rows);
  img.copyTo(c.img(r));
  sheet.corners = {cv::Point2d(r.x - 0.5, r.y - 0.5), cv::Point2d(r.x + r.width - 0.5, r.y - 0.5),
                   cv::Point2d(r.x + r.width - 0.5, r.y + r.height - 0.5),
                   cv::Point2d(r.x - 0.5, r.y + r.height - 0.5)};
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
  c.scaleBar(c.heightMm() - 23);
  footer(c, paper, dpi);
  sheet.image = c.img;
  return sheet;
}

std::vector<std::uint8_t> encodeSheetPng(const cv::Mat& image, double dpi) {
  checkBilevel(image);
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", image, png,
                    {cv::IMWRITE_PNG_BILEVEL, 1, cv::IMWRITE_PNG_COMPRESSION, 9}))
    throw std::runtime_error("PNG encoding failed");
  // pHYs (pixels per metre) right after IHDR (8-byte signature + 25-byte IHDR chunk).
  const std::uint32_t ppm = std::uint32_t(std::lround(dpi / 0.0254));
  std::vector<std::uint8_t> chunk;
  put32(chunk, 9);
  const std::size_t typeAt = chunk.size();
  for (char ch : std::string("pHYs")) chunk.push_back(std::uint8_t(ch));
  put32(chunk, ppm);
  put32(chunk, ppm);
  chunk.push_back(1);  // unit: metre
  put32(chunk, std::uint32_t(::crc32(0, &chunk[typeAt], uInt(chunk.size() - typeAt))));
  png.insert(png.begin() + 33, chunk.begin(), chunk.end());
  return png;
}

std::vector<std::uint8_t> encodeSheetPdf(const cv::Mat& image, double dpi, const Paper& paper,
                                         const std::string& title) {
  const PngParts png = parsePng(encodeSheetPng(image, dpi));
  if (png.bitDepth != 1 || png.colourType != 0 || png.interlace != 0)
    throw std::runtime_error("unexpected PNG layout for the PDF (bit depth " +
                             std::to_string(png.bitDepth) + ")");
  const double pageW = paper.widthMm / 25.4 * 72, pageH = paper.heightMm / 25.4 * 72;
  const double imgW = png.width * 72.0 / dpi, imgH = png.height * 72.0 / dpi;
  std::string out = "%PDF-1.4\n%\xE2\xE3\xCF\xD3\n";
  std::vector<std::size_t> offsets;
  char buf[512];
  auto object = [&](const std::string& body) {
    offsets.push_back(out.size());
    out += std::to_string(offsets.size()) + " 0 obj\n" + body + "\nendobj\n";
  };
  object("<< /Type /Catalog /Pages 2 0 R >>");
  object("<< /Type /Pages /Kids [3 0 R] /Count 1 >>");
  std::snprintf(buf, sizeof buf,
                "<< /Type /Page /Parent 2 0 R /MediaBox [0 0 %.3f %.3f] /Resources << /XObject "
                "<< /Im0 4 0 R >> >> /Contents 5 0 R >>",
                pageW, pageH);
  object(buf);
  std::snprintf(buf, sizeof buf,
                "<< /Type /XObject /Subtype /Image /Width %d /Height %d /ColorSpace /DeviceGray "
                "/BitsPerComponent 1 /Filter /FlateDecode /DecodeParms << /Predictor 15 /Colors 1 "
                "/BitsPerComponent 1 /Columns %d >> /Length %zu >>\nstream\n",
                png.width, png.height, png.width, png.idat.size());
  object(std::string(buf) + std::string(png.idat.begin(), png.idat.end()) + "\nendstream");
  // The image at its physical size, centred (72 points per inch).
  std::snprintf(buf, sizeof buf, "q %.4f 0 0 %.4f %.4f %.4f cm /Im0 Do Q\n", imgW, imgH,
                (pageW - imgW) / 2, (pageH - imgH) / 2);
  const std::string content = buf;
  object("<< /Length " + std::to_string(content.size()) + " >>\nstream\n" + content + "endstream");
  std::string safe;
  for (char ch : title)
    if (ch != '(' && ch != ')' && ch != '\\' && ch >= 32 && ch < 127) safe += ch;
  object("<< /Title (" + safe + ") /Producer (planetsculpt markers) >>");
  const std::size_t xref = out.size();
  out += "xref\n0 " + std::to_string(offsets.size() + 1) + "\n0000000000 65535 f \n";
  for (const std::size_t o : offsets) {
    std::snprintf(buf, sizeof buf, "%010zu 00000 n \n", o);
    out += buf;
  }
  out += "trailer\n<< /Size " + std::to_string(offsets.size() + 1) +
         " /Root 1 0 R /Info 6 0 R >>\nstartxref\n" + std::to_string(xref) + "\n%%EOF\n";
  return {out.begin(), out.end()};
}

}  // namespace ps::tracking
