// The sheets' files (marker_sheet.hpp): the raster as a 1-bit PNG through libpng, the drawing
// steps as a vector PDF through cairo.
#include <cairo-pdf.h>
#include <cairo.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "io/png_codec.hpp"
#include "tracking/marker_sheet.hpp"

namespace ps::tracking {

namespace {

constexpr double kPointsPerMm = 72.0 / 25.4;
// DejaVu Sans (what cairo's "sans-serif" is on Debian): capital letters are 0.729 em tall.
constexpr double kCapHeightEm = 0.729;

cairo_status_t appendBytes(void* closure, const unsigned char* data, unsigned int length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(closure);
  out->insert(out->end(), data, data + length);
  return CAIRO_STATUS_SUCCESS;
}

void draw(cairo_t* cr, const SheetOp& op) {
  switch (op.kind) {
    case SheetOp::Kind::kBox:
      cairo_set_source_rgb(cr, op.black ? 0 : 1, op.black ? 0 : 1, op.black ? 0 : 1);
      cairo_rectangle(cr, op.x0, op.y0, op.x1 - op.x0, op.y1 - op.y0);
      cairo_fill(cr);
      break;
    case SheetOp::Kind::kLine:
      cairo_set_source_rgb(cr, 0, 0, 0);
      cairo_set_line_width(cr, op.size);
      cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
      cairo_move_to(cr, op.x0, op.y0);
      cairo_line_to(cr, op.x1, op.y1);
      cairo_stroke(cr);
      break;
    case SheetOp::Kind::kText: {
      cairo_set_source_rgb(cr, 0, 0, 0);
      cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                             op.bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
      cairo_set_font_size(cr, op.size / kCapHeightEm);
      cairo_text_extents_t ext;
      cairo_text_extents(cr, op.text.c_str(), &ext);
      cairo_move_to(cr, op.centre ? op.x0 - ext.x_advance / 2 : op.x0, op.y0);
      cairo_show_text(cr, op.text.c_str());
      break;
    }
  }
}

}  // namespace

std::vector<std::uint8_t> encodeSheetPng(const cv::Mat& image, double dpi) {
  io::PngWriteOptions o;
  o.bilevel = true;
  o.compression = 9;
  o.pixelsPerMetre = dpi / 0.0254;
  return io::encodePng(image, o);
}

std::vector<std::uint8_t> encodeSheetPdf(const Sheet& sheet) {
  std::vector<std::uint8_t> out;
  const double w = sheet.paper.widthMm * kPointsPerMm, h = sheet.paper.heightMm * kPointsPerMm;
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_pdf_surface_create_for_stream(appendBytes, &out, w, h), cairo_surface_destroy);
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_TITLE, sheet.title.c_str());
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_CREATOR, "planetsculpt markers");
  {
    std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()),
                                                          cairo_destroy);
    cairo_scale(cr.get(), kPointsPerMm, kPointsPerMm);  // user units: millimetres
    cairo_set_antialias(cr.get(), CAIRO_ANTIALIAS_NONE);
    for (const SheetOp& op : sheet.ops) draw(cr.get(), op);
    cairo_show_page(cr.get());
    if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS)
      throw std::runtime_error(std::string("PDF: ") +
                               cairo_status_to_string(cairo_status(cr.get())));
  }
  cairo_surface_finish(surface.get());
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(std::string("PDF: ") +
                             cairo_status_to_string(cairo_surface_status(surface.get())));
  return out;
}

}  // namespace ps::tracking
