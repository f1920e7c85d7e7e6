#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <stdexcept>
#include <system_error>

namespace ps::io {

namespace {
void fsyncPath(const std::filesystem::path& p, bool directory) {
  const int fd = ::open(p.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
  if (fd < 0) return;  // best effort: some filesystems refuse directory fds
  ::fsync(fd);
  ::close(fd);
}
}  // namespace

void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path& tmp)>& write,
                     const std::function<void()>& beforeRename) {
  const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  // Built with append rather than operator+ chains: g++ 12 at -O3 raises a false -Wrestrict there.
  std::string name(1, '.');
  name.append(path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  const auto tmp = dir / name;
  try {
    write(tmp);
    fsyncPath(tmp, false);
    if (beforeRename) beforeRename();
    std::filesystem::rename(tmp, path);
    fsyncPath(dir, true);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}

}  // namespace ps::io
