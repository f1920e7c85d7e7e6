#pragma once
#include <filesystem>
#include <functional>
#include <string>

namespace ps::io {

// Writes a file so that a crash or kill at any moment leaves either the previous file or the
// complete new one: `write` fills a temporary file in the same directory, which is flushed to
// disk and renamed over `path`. Throws std::runtime_error naming the file on any failure.
void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path& tmp)>& write);

}  // namespace ps::io
