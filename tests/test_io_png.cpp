// PNG through libpng (io/png_codec): what is written reads back the same, pixel for pixel, with
// its text and physical size; OpenCV's decoder reads the same pixels; a damaged stream is
// refused with libpng's reason, never read as something else.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "io/png_codec.hpp"

using namespace ps;

namespace {

cv::Mat randomImage(int type, std::uint32_t seed) {
  cv::Mat m(37, 53, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 65536 : 256);
  return m;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

}  // namespace

TEST(IoPng, EveryTypeRoundTripsWithItsTextAndSize) {
  for (int type : {CV_8UC1, CV_8UC3, CV_16UC1}) {
    const cv::Mat img = randomImage(type, std::uint32_t(type + 1));
    io::PngWriteOptions o;
    o.text = {{"planetsculpt:min_m", "-8123.5"}, {"Comment", "two words"}};
    o.pixelsPerMetre = 11811;
    const auto png = io::encodePng(img, o);
    io::PngReader r(png);
    EXPECT_EQ(r.header().width, img.cols);
    EXPECT_EQ(r.header().height, img.rows);
    EXPECT_EQ(r.header().bitDepth, type == CV_16UC1 ? 16 : 8);
    EXPECT_EQ(r.header().pixelsPerMetre, 11811.0);
    EXPECT_EQ(r.text(), o.text) << "tEXt chunks come before the image data";
    EXPECT_TRUE(same(r.pixels(), img)) << "type " << type;
    // Another decoder reads the same pixels.
    EXPECT_TRUE(same(cv::imdecode(png, cv::IMREAD_UNCHANGED), img)) << "type " << type;
  }
}

TEST(IoPng, BilevelImagesPackToOneBitAndComeBackAsZeroOrOne) {
  cv::Mat img = randomImage(CV_8UC1, 7);
  cv::threshold(img, img, 127, 255, cv::THRESH_BINARY);
  io::PngWriteOptions o;
  o.bilevel = true;
  const auto png = io::encodePng(img, o);
  io::PngReader r(png);
  EXPECT_EQ(r.header().bitDepth, 1);
  const cv::Mat back = r.pixels();  // expanded to 8 bits: 0 and 255
  EXPECT_TRUE(same(back, img));
  img.at<uchar>(3, 4) = 128;
  EXPECT_THROW(io::encodePng(img, o), std::invalid_argument);
}

TEST(IoPng, DamagedStreamsAreRefusedWithTheReason) {
  const cv::Mat img = randomImage(CV_16UC1, 3);
  const auto png = io::encodePng(img, {.text = {{"k", "v"}}});
  EXPECT_THROW(io::PngReader(std::span<const unsigned char>(png).first(7)),
               io::PngError);  // no signature
  // Each byte of the image data flipped in turn (a sample): a CRC or zlib error, or (in the
  // rare case both agree) an image of the declared size, never a crash.
  std::mt19937 rng(5);
  for (int k = 0; k < 200; ++k) {
    auto bad = png;
    const std::size_t at = 8 + rng() % (bad.size() - 8);
    bad[at] ^= std::uint8_t(1 + rng() % 255);
    try {
      io::PngReader r(bad);
      const cv::Mat m = r.pixels();
      EXPECT_EQ(m.size(), img.size()) << "byte " << at;
    } catch (const io::PngError& e) {
      EXPECT_STRNE(e.what(), "") << "byte " << at;
    }
  }
  // Cut short: refused, naming the truncation or the missing data.
  for (std::size_t n : {std::size_t(20), std::size_t(40), png.size() / 2, png.size() - 13}) {
    EXPECT_THROW(
        {
          io::PngReader r(std::span<const unsigned char>(png).first(n));
          (void)r.pixels();
        },
        io::PngError)
        << n << " bytes";
  }
}

// A chunk that declares more bytes than the stream holds is refused without allocating them
// (libpng allocates a chunk's declared length before reading it: 2 GB for a 300-byte stream).
TEST(IoPng, AChunkLongerThanTheStreamAllocatesNothingLikeIt) {
  const auto png = io::encodePng(randomImage(CV_16UC1, 4), {});
  std::vector<unsigned char> bad(png.begin(), png.begin() + 33);  // signature + IHDR
  const unsigned char chunk[] = {0x7f, 0xff, 0xff, 0xf0, 't', 'E', 'X', 't'};
  bad.insert(bad.end(), std::begin(chunk), std::end(chunk));
  bad.resize(bad.size() + 200, 'a');
  rusage before{}, after{};
  getrusage(RUSAGE_SELF, &before);
  EXPECT_THROW(
      {
        io::PngReader r(bad);
        (void)r.pixels();
      },
      io::PngError);
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 200 * 1024) << "KiB more resident at the peak";
}

TEST(IoPng, BadRequestsAreRefused) {
  EXPECT_THROW(io::encodePng(cv::Mat(4, 4, CV_32F)), std::invalid_argument);
  EXPECT_THROW(io::encodePng(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(io::encodePng(cv::Mat(4, 4, CV_8U), {.text = {{"", "x"}}}), std::invalid_argument);
  EXPECT_THROW(io::encodePng(cv::Mat(4, 4, CV_8U), {.text = {{std::string(80, 'k'), "x"}}}),
               std::invalid_argument);
  io::PngWriteOptions level;
  level.compression = 10;
  EXPECT_THROW(io::encodePng(cv::Mat(4, 4, CV_8U), level), std::invalid_argument);
}
