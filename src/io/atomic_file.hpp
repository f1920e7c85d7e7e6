#pragma once
#include <filesystem>
#include <functional>
#include <string>

namespace ps::io {

// Writes a file so that a crash or kill at any moment leaves either the previous file or the
// complete new one: `write` fills a temporary file in the same directory, which is flushed to
// disk and renamed over `path`. Throws std::runtime_error naming the file on any failure.
// `beforeRename`, when given, runs once the temporary file is on disk, just before the rename
// (an exception from it leaves `path` as it was).
void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path& tmp)>& write,
                     const std::function<void()>& beforeRename = nullptr);

}  // namespace ps::io
