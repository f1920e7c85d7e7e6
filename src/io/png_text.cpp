#include "io/png_text.hpp"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include <zlib.h>

namespace ps::io {

namespace {

constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

std::uint32_t readBe32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         p[3];
}
void appendBe32(std::vector<unsigned char>& out, std::uint32_t x) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<unsigned char>(x >> s));
}

}  // namespace

std::vector<unsigned char> addPngTextChunks(
    const std::vector<unsigned char>& png,
    const std::vector<std::pair<std::string, std::string>>& entries) {
  if (png.size() < 33 || std::memcmp(png.data(), kSignature, 8) != 0 ||
      std::memcmp(png.data() + 12, "IHDR", 4) != 0) {
    throw std::invalid_argument("not a PNG stream");
  }
  const std::size_t ihdrEnd = 8 + 12 + readBe32(png.data() + 8);
  std::vector<unsigned char> out(png.begin(), png.begin() + std::ptrdiff_t(ihdrEnd));
  for (const auto& [key, value] : entries) {
    std::vector<unsigned char> chunk = {'t', 'E', 'X', 't'};
    chunk.insert(chunk.end(), key.begin(), key.end());
    chunk.push_back(0);
    chunk.insert(chunk.end(), value.begin(), value.end());
    appendBe32(out, std::uint32_t(chunk.size() - 4));
    out.insert(out.end(), chunk.begin(), chunk.end());
    appendBe32(out, std::uint32_t(::crc32(0, chunk.data(), uInt(chunk.size()))));
  }
  out.insert(out.end(), png.begin() + std::ptrdiff_t(ihdrEnd), png.end());
  return out;
}

std::vector<std::pair<std::string, std::string>> readPngTextChunks(
    const std::vector<unsigned char>& png) {
  std::vector<std::pair<std::string, std::string>> out;
  if (png.size() < 8 || std::memcmp(png.data(), kSignature, 8) != 0)
    throw std::invalid_argument("not a PNG stream");
  std::size_t p = 8;
  while (p + 12 <= png.size()) {
    const std::uint32_t len = readBe32(png.data() + p);
    if (p + 12 + len > png.size()) throw std::invalid_argument("truncated PNG chunk");
    if (std::memcmp(png.data() + p + 4, "tEXt", 4) == 0) {
      const auto* d = png.data() + p + 8;
      const auto* nul = static_cast<const unsigned char*>(std::memchr(d, 0, len));
      if (nul) out.emplace_back(std::string(d, nul), std::string(nul + 1, d + len));
    }
    p += 12 + len;
  }
  return out;
}

}  // namespace ps::io
