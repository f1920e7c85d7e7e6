#pragma once
// An empty scratch folder per test process: TMP/ps_test_<name>_<pid>, emptied first.
#include <unistd.h>

#include <filesystem>
#include <string>

namespace ps::testkit {

inline std::filesystem::path freshDir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() /
                 ("ps_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace ps::testkit
