// The sheets drawn through cairo (marker_sheet.hpp): one function paints a sheet's steps onto any
// cairo surface, an image surface for the sheet's pixels (the PNG, through libpng as 1 bit with
// its resolution) or a PDF surface for the vector PDF.
#include <cairo-pdf.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>

#include "io/png_codec.hpp"
#include "tracking/marker_sheet.hpp"

namespace ps::tracking {

namespace {

constexpr double kPointsPerMm = 72.0 / 25.4;
// DejaVu Sans (what cairo's "sans-serif" is on Debian): capital letters are 0.729 em tall.
constexpr double kCapHeightEm = 0.729;
// The image is painted in bands of this many rows: an A4 page at 1200 dpi as one RGB24 surface
// would take 557 MB, a band takes 41 MB.
constexpr int kBandRows = 1024;

using Surface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using Context = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

cairo_status_t appendBytes(void* closure, const unsigned char* data, unsigned int length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(closure);
  out->insert(out->end(), data, data + length);
  return CAIRO_STATUS_SUCCESS;
}

void fillBox(cairo_t* cr, const SheetOp& op, bool pixels) {
  cairo_set_source_rgb(cr, op.black ? 0 : 1, op.black ? 0 : 1, op.black ? 0 : 1);
  if (!pixels) {
    cairo_rectangle(cr, op.x0, op.y0, op.x1 - op.x0, op.y1 - op.y0);
    cairo_fill(cr);
    return;
  }
  // On pixels, the box's edges on the nearest pixel boundaries: a marker's cells tile exactly,
  // each a whole number of pixels, and the marker's corners are where Sheet::corners says.
  double x0 = op.x0, y0 = op.y0, x1 = op.x1, y1 = op.y1;
  cairo_user_to_device(cr, &x0, &y0);
  cairo_user_to_device(cr, &x1, &y1);
  x0 = std::floor(x0 + 0.5), y0 = std::floor(y0 + 0.5);
  x1 = std::floor(x1 + 0.5), y1 = std::floor(y1 + 0.5);
  cairo_save(cr);
  cairo_identity_matrix(cr);
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  cairo_fill(cr);
  cairo_restore(cr);
}

void strokeLine(cairo_t* cr, const SheetOp& op, bool pixels) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  double width = op.size, unused = 0;
  if (pixels) {  // at least a pixel wide, so that a thin line never falls between pixel centres
    double device = op.size;
    cairo_user_to_device_distance(cr, &device, &unused);
    if (device < 1) width = op.size / device;
  }
  cairo_set_line_width(cr, width);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  cairo_move_to(cr, op.x0, op.y0);
  cairo_line_to(cr, op.x1, op.y1);
  cairo_stroke(cr);
}

void showText(cairo_t* cr, const SheetOp& op) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         op.bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, op.size / kCapHeightEm);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, op.text.c_str(), &ext);
  cairo_move_to(cr, op.centre ? op.x0 - ext.x_advance / 2 : op.x0, op.y0);
  cairo_show_text(cr, op.text.c_str());
}

// The one drawing of a sheet: its steps on `cr`, whose user units are millimetres from the page's
// top-left corner. On an image surface nothing is antialiased (the image holds black and white
// only) and the text keeps the PDF's unhinted metrics.
void drawSheet(cairo_t* cr, const std::vector<SheetOp>& ops) {
  const bool pixels = cairo_surface_get_type(cairo_get_target(cr)) == CAIRO_SURFACE_TYPE_IMAGE;
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);
  if (pixels) {
    std::unique_ptr<cairo_font_options_t, decltype(&cairo_font_options_destroy)> font(
        cairo_font_options_create(), cairo_font_options_destroy);
    cairo_font_options_set_antialias(font.get(), CAIRO_ANTIALIAS_NONE);
    cairo_font_options_set_hint_style(font.get(), CAIRO_HINT_STYLE_NONE);
    cairo_font_options_set_hint_metrics(font.get(), CAIRO_HINT_METRICS_OFF);
    cairo_set_font_options(cr, font.get());
  }
  for (const SheetOp& op : ops) {
    switch (op.kind) {
      case SheetOp::Kind::kBox:
        fillBox(cr, op, pixels);
        break;
      case SheetOp::Kind::kLine:
        strokeLine(cr, op, pixels);
        break;
      case SheetOp::Kind::kText:
        showText(cr, op);
        break;
    }
  }
}

void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(std::string(what) + ": " + cairo_status_to_string(status));
}

}  // namespace

cv::Mat rasterizeSheet(const std::vector<SheetOp>& ops, cv::Size size, double dpi) {
  cv::Mat out(size, CV_8U);
  for (int top = 0; top < size.height; top += kBandRows) {
    const int rows = std::min(kBandRows, size.height - top);
    Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, size.width, rows),
                    cairo_surface_destroy);
    check(cairo_surface_status(surface.get()), "sheet image");
    {
      Context cr(cairo_create(surface.get()), cairo_destroy);
      cairo_set_source_rgb(cr.get(), 1, 1, 1);  // the paper
      cairo_paint(cr.get());
      cairo_translate(cr.get(), 0, -top);
      cairo_scale(cr.get(), dpi / 25.4, dpi / 25.4);  // user units: millimetres
      drawSheet(cr.get(), ops);
      check(cairo_status(cr.get()), "sheet image");
    }
    cairo_surface_flush(surface.get());
    const unsigned char* data = cairo_image_surface_get_data(surface.get());
    const int stride = cairo_image_surface_get_stride(surface.get());
    for (int r = 0; r < rows; ++r) {
      const auto* px = reinterpret_cast<const std::uint32_t*>(data + std::ptrdiff_t(r) * stride);
      auto* row = out.ptr<std::uint8_t>(top + r);
      for (int x = 0; x < size.width; ++x) row[x] = (px[x] & 0xff) >= 128 ? 255 : 0;  // blue
    }
  }
  return out;
}

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
  Surface surface(cairo_pdf_surface_create_for_stream(appendBytes, &out, w, h),
                  cairo_surface_destroy);
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_TITLE, sheet.title.c_str());
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_CREATOR, "planetsculpt markers");
  {
    Context cr(cairo_create(surface.get()), cairo_destroy);
    cairo_scale(cr.get(), kPointsPerMm, kPointsPerMm);  // user units: millimetres
    drawSheet(cr.get(), sheet.ops);
    cairo_show_page(cr.get());
    check(cairo_status(cr.get()), "PDF");
  }
  cairo_surface_finish(surface.get());
  check(cairo_surface_status(surface.get()), "PDF");
  return out;
}

}  // namespace ps::tracking
