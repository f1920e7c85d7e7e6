#pragma once
// PNG through libpng: the heightmaps' 16-bit grey PNGs with their tEXt metadata, the marker
// sheets' 1-bit PNGs with their physical size (pHYs), and the reader that checks a file's
// header before it decodes the pixels. libpng writes and parses the chunks (tEXt, pHYs, CRCs);
// nothing here assembles PNG bytes by hand.
#include <cstddef>
#include <opencv2/core.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ps::io {

using PngText = std::vector<std::pair<std::string, std::string>>;

struct PngWriteOptions {
  PngText text;               // tEXt chunks, before the image data (keys of 1-79 Latin-1 chars)
  double pixelsPerMetre = 0;  // > 0: a pHYs chunk (the printed size of a sheet)
  int compression = 6;        // zlib level 0-9
  bool bilevel = false;       // 1-bit grey: every pixel of the 8-bit image must be 0 or 255
};

// CV_8UC1 (grey), CV_8UC3 (BGR, written as RGB) or CV_16UC1. std::invalid_argument for other
// types, a bilevel image with other values, or a bad key.
std::vector<unsigned char> encodePng(const cv::Mat& image, const PngWriteOptions& options = {});

// A PNG file's header as libpng reads it.
struct PngHeader {
  int width = 0, height = 0;
  int bitDepth = 0;
  int colourType = 0;  // PNG's: 0 grey, 2 RGB, 3 palette, 4 grey + alpha, 6 RGBA
  bool interlaced = false;
  double pixelsPerMetre = 0;  // 0: no pHYs in metres
};

// Thrown for a stream libpng refuses (not a PNG, a bad CRC, truncated data), with its message.
class PngError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads a PNG in two steps, so that a caller can refuse a file by its header before the pixels
// are decoded. The bytes must outlive the reader.
class PngReader {
 public:
  explicit PngReader(std::span<const unsigned char> bytes);  // reads the header; PngError
  ~PngReader();
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;

  const PngHeader& header() const { return header_; }
  // The pixels as stored: grey 8 or 16 bits as CV_8UC1 / CV_16UC1, RGB(A) as BGR(A); then the
  // chunks after the image data. PngError for corrupt data.
  cv::Mat pixels();
  // tEXt, zTXt and iTXt chunks read so far: those before the image data after construction,
  // all of them after pixels().
  PngText text() const;

  struct State;  // libpng's structs and the read position (png_codec.cpp)

 private:
  State* s_;
  PngHeader header_;
};

}  // namespace ps::io
