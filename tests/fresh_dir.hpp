#pragma once
// Scratch folders for tests, and reading and writing a file's bytes: TMP/ps_test_<name>_<pid>,
// emptied first and removed when the test process ends (named per process, they would otherwise
// pile up in TMP run after run). A process with a failed test keeps them, as evidence.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <system_error>
#include <vector>

namespace ps::testkit {

class ScratchFolders {
 public:
  static void add(const std::filesystem::path& dir) { instance().dirs_.push_back(dir); }
  ~ScratchFolders() {
    if (::testing::UnitTest::GetInstance()->Failed()) return;
    for (const auto& d : dirs_) {
      std::error_code ignored;  // a folder already gone is fine
      std::filesystem::remove_all(d, ignored);
    }
  }

 private:
  static ScratchFolders& instance() {
    static ScratchFolders folders;
    return folders;
  }
  std::vector<std::filesystem::path> dirs_;
};

inline std::filesystem::path freshDir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() /
                 ("ps_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  ScratchFolders::add(d);
  return d;
}

// A file's bytes (empty when it cannot be read).
inline std::vector<unsigned char> readAll(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// Writes `bytes` to p, replacing it.
inline void writeAll(const std::filesystem::path& p, std::span<const unsigned char> bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

inline void writeText(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

}  // namespace ps::testkit
