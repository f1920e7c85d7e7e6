#pragma once
// Where this build's source tree lies, and the shared data folder beside it (SOURCE/../shared),
// as CMake configured them. The paths live in one generated file (build_paths.cpp.in, written
// into the build folder), so that a clone in another folder recompiles that file alone and a
// compiler cache serves every other object (docs/CI.md).
#include <filesystem>

namespace ps::app {

std::filesystem::path sourceDir();
std::filesystem::path sharedDir();

}  // namespace ps::app
