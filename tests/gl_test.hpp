#pragma once
// Tests that draw with headless OpenGL: skipped with a message where EGL is missing.
#include <gtest/gtest.h>

#include <atomic>
#include <string>

#include "render/egl_context.hpp"

namespace ps::testkit {

// Mesa's llvmpipe keeps allocations made from its JIT-compiled code until exit; their stacks
// end in code that belongs to no module, so no LSan suppression can name them. Leak checking is
// off for a test process that made a GL context (ctest runs one test per process) and on for
// all the others (__lsan_is_turned_off in test_render.cpp reads this).
inline std::atomic<bool> madeGlContext{false};

}  // namespace ps::testkit

#define SKIP_WITHOUT_GL()                                                              \
  do {                                                                                 \
    ps::testkit::madeGlContext = true;                                                 \
    std::string why;                                                                   \
    if (!render::headlessGlAvailable(&why)) GTEST_SKIP() << "no headless GL: " << why; \
  } while (0)
