#pragma once
#include <cstdint>
#include <string>

namespace ps::app {

struct DemoOptions {
  std::string outDir = "out/demo";
  int gridLevel = 12;  // 4097^2
  std::uint64_t seed = 1;
  std::string strokes;  // stroke script; "" = the bundled data/demo-strokes.txt when present
  double distMaxPx = 4.0;
  std::size_t triangleBudget = 70000;
};

// The main job: make the default planet, sculpt it with the bundled stroke script, write its
// heightmap (16-bit PNG + sidecar), a relief preview, and a tessellated view (OBJ + PNG).
int runDemo(const DemoOptions& options);

}  // namespace ps::app
