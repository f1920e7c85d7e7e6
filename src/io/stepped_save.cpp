#include "io/stepped_save.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <stdexcept>
#include <system_error>

#include "io/atomic_file.hpp"

namespace ps::io {

namespace {

void writeAll(int fd, const unsigned char* p, std::size_t n, const std::filesystem::path& path) {
  while (n > 0) {
    const ssize_t k = ::write(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0)
      throw std::runtime_error("cannot write " + path.string() + ": " +
                               std::system_category().message(errno));
    p += k;
    n -= std::size_t(k);
  }
}

}  // namespace

std::uint32_t savePlanetInSteps(const core::Chart& chart, std::span<const float> heights,
                                terrain::ErrorRule rule, const std::filesystem::path& path,
                                const SteppedSave& steps, const PlanetSaveOptions& options) {
  static_assert(std::endian::native == std::endian::little,
                "the stepped save writes the heights' memory as the file's float32 LE");
  if (heights.size() != chart.grid().count())
    throw std::invalid_argument("planet has " + std::to_string(heights.size()) +
                                " heights, its grid needs " + std::to_string(chart.grid().count()));
  const auto* bytes = reinterpret_cast<const unsigned char*>(heights.data());
  const std::size_t total = heights.size_bytes();
  const std::size_t step = std::max<std::size_t>(steps.stepBytes, 4096);
  auto between = [&] {
    if (steps.between) steps.between();
  };
  std::uint32_t heightsCrc = std::uint32_t(::crc32(0, nullptr, 0));
  for (std::size_t at = 0; at < total; at += step) {
    const std::size_t k = std::min(step, total - at);
    heightsCrc = std::uint32_t(::crc32(heightsCrc, bytes + at, uInt(k)));
    between();
  }
  const PlanetPrologue prologue = planetPrologue(chart, rule, heightsCrc, options);
  writeAtomically(
      path,
      [&](const std::filesystem::path& tmp) {
        const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        if (fd < 0)
          throw std::runtime_error("cannot create " + tmp.string() + " to save " + path.string());
        try {
          writeAll(fd, prologue.header.data(), prologue.header.size(), path);
          writeAll(fd, reinterpret_cast<const unsigned char*>(prologue.metadata.data()),
                   prologue.metadata.size(), path);
          for (std::size_t at = 0; at < total; at += step) {
            writeAll(fd, bytes + at, std::min(step, total - at), path);
            // Flushed step by step, so the final flush before the rename is short.
            if (::fdatasync(fd) != 0)
              throw std::runtime_error("cannot flush " + path.string() + " to disk (disk full?)");
            // On disk now: its page cache can go, so that saving 256 MiB again and again does
            // not push the machine's memory into reclaim (which stalls the frame loop too).
            const std::size_t done = std::min(step, total - at);
            (void)::posix_fadvise(fd, off_t(kPlanetHeaderBytes + prologue.metadata.size() + at),
                                  off_t(done), POSIX_FADV_DONTNEED);
            between();
          }
        } catch (...) {
          ::close(fd);
          throw;
        }
        if (::close(fd) != 0) throw std::runtime_error("cannot write " + path.string());
      },
      [&] {
        if (steps.beforeRename) steps.beforeRename(heightsCrc);
      });
  return heightsCrc;
}

}  // namespace ps::io
