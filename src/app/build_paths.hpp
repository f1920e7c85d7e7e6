#pragma once
// Where this build's source tree lies, the shared data folder beside it (SOURCE/../shared) and
// the program it builds, as CMake configured them. The paths live in one generated file
// (build_paths.cpp.in, written into the build folder), so that a clone in another folder recompiles
// that file alone and a compiler cache serves every other object (docs/CI.md). The environment
// variable PLANETSCULPT_SOURCE_DIR, when set, replaces the source tree (and so the shared folder
// beside it): a binary run against a copy of the tree elsewhere. PS_SHARED_DIR, when set, names
// the shared folder itself (a checkout that is not beside it; docs/CI.md).
#include <filesystem>

namespace ps::app {

std::filesystem::path sourceDir();
std::filesystem::path sharedDir();
// This build's `planetsculpt` (the tests that run a command end to end); empty where the build
// has no program (PS_BUILD_APP=OFF).
std::filesystem::path commandPath();

}  // namespace ps::app
