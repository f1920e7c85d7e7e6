#include "io/png_codec.hpp"

#include <png.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>

namespace ps::io {

// libpng reports errors through a callback that must not return: it stores the message and
// jumps back to the setjmp of the function that called libpng, which then throws. Between a
// setjmp and its longjmp only libpng calls run, and what they change lives on the heap.
// Named, not anonymous: PngReader::State (a member of the header's class) holds one.
namespace png_detail {
struct ErrorSink {
  char message[256] = {0};
};
}  // namespace png_detail

namespace {

[[noreturn]] void onError(png_structp png, png_const_charp what) {
  auto* sink = static_cast<png_detail::ErrorSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof sink->message, "%s", what ? what : "libpng error");
  std::longjmp(png_jmpbuf(png), 1);
}

void onWarning(png_structp, png_const_charp) {}  // benign (e.g. an unknown ancillary chunk)

void onWrite(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + n);
}

void onFlush(png_structp) {}

// Everything libpng's writer needs, prepared before it runs (nothing on the stack of the
// function that calls setjmp changes after it).
struct WriteJob {
  png_bytep* rows = nullptr;
  png_uint_32 width = 0, height = 0;
  int depth = 8, colour = PNG_COLOR_TYPE_GRAY;
  png_text* text = nullptr;
  int textCount = 0;
  png_uint_32 pixelsPerMetre = 0;
  int compression = 6;
  std::vector<unsigned char>* out = nullptr;
  png_detail::ErrorSink sink;
  png_structp png = nullptr;
  png_infop info = nullptr;
};

// False (with the message in job->sink) when libpng refuses.
bool writePng(WriteJob* job) {
  job->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &job->sink, onError, onWarning);
  if (!job->png) return false;
  job->info = png_create_info_struct(job->png);
  if (!job->info || setjmp(png_jmpbuf(job->png))) {
    png_destroy_write_struct(&job->png, &job->info);
    return false;
  }
  png_set_write_fn(job->png, job->out, onWrite, onFlush);
  png_set_compression_level(job->png, job->compression);
  png_set_IHDR(job->png, job->info, job->width, job->height, job->depth, job->colour,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (job->textCount > 0) png_set_text(job->png, job->info, job->text, job->textCount);
  if (job->pixelsPerMetre > 0)
    png_set_pHYs(job->png, job->info, job->pixelsPerMetre, job->pixelsPerMetre,
                 PNG_RESOLUTION_METER);
  png_write_info(job->png, job->info);
  if (job->colour == PNG_COLOR_TYPE_RGB) png_set_bgr(job->png);
  if (job->depth == 16 && std::endian::native == std::endian::little) png_set_swap(job->png);
  png_write_image(job->png, job->rows);
  png_write_end(job->png, nullptr);
  png_destroy_write_struct(&job->png, &job->info);
  return true;
}

}  // namespace

std::vector<unsigned char> encodePng(const cv::Mat& image, const PngWriteOptions& o) {
  const int type = image.type();
  if (type != CV_8UC1 && type != CV_8UC3 && type != CV_16UC1)
    throw std::invalid_argument("PNG: images must be 8-bit grey, 8-bit BGR or 16-bit grey");
  if (image.empty()) throw std::invalid_argument("PNG: empty image");
  if (o.bilevel && type != CV_8UC1) throw std::invalid_argument("PNG: bilevel needs 8-bit grey");
  if (o.compression < 0 || o.compression > 9)
    throw std::invalid_argument("PNG: compression level must be 0-9");
  // Rows as libpng takes them: a bilevel image packed 8 pixels to a byte (MSB first, 1 white).
  std::vector<std::vector<unsigned char>> packed;
  std::vector<png_bytep> rows(std::size_t(image.rows));
  for (int y = 0; y < image.rows; ++y) {
    if (!o.bilevel) {
      rows[std::size_t(y)] = const_cast<png_bytep>(image.ptr<unsigned char>(y));
      continue;
    }
    auto& row = packed.emplace_back(std::size_t((image.cols + 7) / 8), 0);
    const unsigned char* src = image.ptr<unsigned char>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (src[x] != 0 && src[x] != 255)
        throw std::invalid_argument("PNG: a bilevel image holds only 0 and 255");
      if (src[x]) row[std::size_t(x / 8)] |= static_cast<unsigned char>(0x80 >> (x % 8));
    }
    rows[std::size_t(y)] = row.data();
  }
  std::vector<png_text> text(o.text.size());
  for (std::size_t i = 0; i < o.text.size(); ++i) {
    const auto& [key, value] = o.text[i];
    if (key.empty() || key.size() > 79 || key.find('\0') != std::string::npos)
      throw std::invalid_argument("PNG: text key '" + key + "' must be 1-79 characters");
    text[i].compression = PNG_TEXT_COMPRESSION_NONE;
    text[i].key = const_cast<char*>(key.c_str());
    text[i].text = const_cast<char*>(value.c_str());
    text[i].text_length = value.size();
  }
  WriteJob job;
  job.rows = rows.data();
  job.width = png_uint_32(image.cols);
  job.height = png_uint_32(image.rows);
  job.depth = type == CV_16UC1 ? 16 : (o.bilevel ? 1 : 8);
  job.colour = type == CV_8UC3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY;
  job.text = text.data();
  job.textCount = int(text.size());
  job.pixelsPerMetre = png_uint_32(std::lround(std::max(0.0, o.pixelsPerMetre)));
  job.compression = o.compression;
  std::vector<unsigned char> out;
  job.out = &out;
  if (!writePng(&job)) throw std::invalid_argument(std::string("PNG: ") + job.sink.message);
  return out;
}

struct PngReader::State {
  std::span<const unsigned char> bytes;
  std::size_t pos = 0;
  png_detail::ErrorSink sink;
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::vector<png_bytep> rows;
  int channels = 0, depth = 0;
  bool done = false;
  std::string broken;  // libpng's complaint after a readable header
};

namespace {

// The transformations (grey stays grey at its depth; a palette and low grey depths expand to 8
// bits; colour comes out as BGR(A); 16-bit samples in this machine's byte order), then the
// output's layout into `s`. False when libpng refuses.
bool prepareRead(PngReader::State* s, bool interlaced) {
  if (setjmp(png_jmpbuf(s->png))) return false;
  png_set_expand(s->png);  // palette -> RGB, grey 1/2/4 -> 8, tRNS -> alpha
  png_set_bgr(s->png);
  if (std::endian::native == std::endian::little) png_set_swap(s->png);
  if (interlaced) png_set_interlace_handling(s->png);
  png_read_update_info(s->png, s->info);
  s->channels = png_get_channels(s->png, s->info);
  s->depth = png_get_bit_depth(s->png, s->info);
  return true;
}

// The image data into s->rows, and the chunks after it. False when libpng refuses.
bool readRows(PngReader::State* s) {
  if (setjmp(png_jmpbuf(s->png))) return false;
  png_read_image(s->png, s->rows.data());
  png_read_end(s->png, s->info);
  return true;
}

// The header (and the chunks before the image data). False when libpng refuses.
bool readHeader(PngReader::State* s) {
  if (setjmp(png_jmpbuf(s->png))) return false;
  png_read_info(s->png, s->info);
  return true;
}

// The stream up to the first chunk (other than image data, which libpng reads in pieces) that
// declares more bytes than the stream has left. libpng allocates and clears such a chunk's
// declared length before reading it, and only warns that it is too large: a 300-byte stream
// declaring a 2 GB text chunk cost 2 GB (fuzz_heightmap_image, kept in its corpus). Cut there,
// the stream reads as what it is, truncated.
std::span<const unsigned char> withoutOverlongChunk(std::span<const unsigned char> b) {
  std::size_t at = 8;  // after the signature
  while (b.size() >= 8 && at + 8 <= b.size()) {
    const unsigned char* h = b.data() + at;
    const std::size_t length = std::size_t(h[0]) << 24 | std::size_t(h[1]) << 16 |
                               std::size_t(h[2]) << 8 | std::size_t(h[3]);
    const bool imageData = std::memcmp(h + 4, "IDAT", 4) == 0;
    if (length > b.size() - at - 8 && !imageData) return b.first(at);
    if (std::memcmp(h + 4, "IEND", 4) == 0 || length > b.size() - at - 8) break;
    at += 12 + length;  // length, type, data, CRC
  }
  return b;
}

void onRead(png_structp png, png_bytep out, png_size_t n) {
  auto* s = static_cast<PngReader::State*>(png_get_io_ptr(png));
  if (n > s->bytes.size() - s->pos) png_error(png, "the file ends inside a chunk (truncated)");
  std::memcpy(out, s->bytes.data() + s->pos, n);
  s->pos += n;
}

}  // namespace

PngReader::PngReader(std::span<const unsigned char> bytes) : s_(new State) {
  s_->bytes = withoutOverlongChunk(bytes);
  std::string refused;
  if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0) {
    refused = "not a PNG stream (no PNG signature)";
  } else {
    s_->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &s_->sink, onError, onWarning);
    if (s_->png) s_->info = png_create_info_struct(s_->png);
    if (!s_->png || !s_->info) {
      refused = "libpng could not start";
    } else {
      png_set_read_fn(s_->png, s_, onRead);
      // The caller refuses sizes by its own limits, with its own message.
      png_set_user_limits(s_->png, PNG_UINT_31_MAX, PNG_UINT_31_MAX);
      // A stream that breaks after a readable IHDR keeps its header, so that the caller can
      // refuse it by its size first; pixels() reports the break.
      if (!readHeader(s_)) {
        if (png_get_image_width(s_->png, s_->info) > 0)
          s_->broken = s_->sink.message;
        else
          refused = s_->sink.message;
      }
    }
  }
  if (!refused.empty()) {
    png_destroy_read_struct(&s_->png, &s_->info, nullptr);
    delete s_;
    throw PngError(refused);
  }
  header_.width = int(png_get_image_width(s_->png, s_->info));
  header_.height = int(png_get_image_height(s_->png, s_->info));
  header_.bitDepth = png_get_bit_depth(s_->png, s_->info);
  header_.colourType = png_get_color_type(s_->png, s_->info);
  header_.interlaced = png_get_interlace_type(s_->png, s_->info) != PNG_INTERLACE_NONE;
  png_uint_32 rx = 0, ry = 0;
  int unit = 0;
  if (png_get_pHYs(s_->png, s_->info, &rx, &ry, &unit) && unit == PNG_RESOLUTION_METER)
    header_.pixelsPerMetre = double(rx);
}

PngReader::~PngReader() {
  png_destroy_read_struct(&s_->png, &s_->info, nullptr);
  delete s_;
}

cv::Mat PngReader::pixels() {
  if (s_->done) throw PngError("the pixels were read already");
  s_->done = true;
  if (!s_->broken.empty()) throw PngError(s_->broken);
  if (!prepareRead(s_, header_.interlaced)) throw PngError(s_->sink.message);
  cv::Mat image(header_.height, header_.width,
                CV_MAKETYPE(s_->depth == 16 ? CV_16U : CV_8U, s_->channels));
  s_->rows.resize(std::size_t(header_.height));
  for (int y = 0; y < header_.height; ++y) s_->rows[std::size_t(y)] = image.ptr<unsigned char>(y);
  if (!readRows(s_)) throw PngError(s_->sink.message);
  return image;
}

PngText PngReader::text() const {
  PngText out;
  png_textp text = nullptr;
  const int n = png_get_text(s_->png, s_->info, &text, nullptr);
  for (int i = 0; i < n; ++i) out.emplace_back(text[i].key, text[i].text ? text[i].text : "");
  return out;
}

}  // namespace ps::io
