#pragma once
// The interpolation kernels of import and export's resampling (heightmap_import.cpp,
// heightmap_export.cpp): bilinear, and Catmull-Rom cubic (Keys, a = -0.5), which reproduces
// quadratics and roughly halves the error of a round trip through the grid on smooth relief
// (docs/EXPORT.md's import section gives the measured figures). Samples at integer coordinates; x
// wraps round a period when asked, y (and x otherwise) clamps to the edge.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace ps::io {

enum class Interpolation { kBilinear, kCubic };
std::string toString(Interpolation i);
Interpolation interpolationFromString(const std::string& s);  // core::InputError

namespace resample_detail {

inline int wrapIndex(int i, int period) {
  i %= period;
  return i < 0 ? i + period : i;
}

// Catmull-Rom weights of the samples at floor(t) - 1 .. floor(t) + 2 for the fraction f.
inline std::array<double, 4> cubicWeights(double f) {
  const double f2 = f * f, f3 = f2 * f;
  return {-0.5 * f3 + f2 - 0.5 * f, 1.5 * f3 - 2.5 * f2 + 1.0, -1.5 * f3 + 2.0 * f2 + 0.5 * f,
          0.5 * f3 - 0.5 * f2};
}

}  // namespace resample_detail

// Samples at(xi, yi) at (x, y) with no clamping or wrapping: at() answers for every index the
// stencil reads (floor(x) - 1 .. floor(x) + 2 for cubic, floor(x) .. floor(x) + 1 for bilinear),
// e.g. a chart's grid read across its glued sides.
template <class At>
double sampleUnclamped(const At& at, double x, double y, Interpolation how) {
  using namespace resample_detail;
  const double xf = std::floor(x), yf = std::floor(y);
  const int x0 = int(xf), y0 = int(yf);
  const double fx = x - xf, fy = y - yf;
  if (how == Interpolation::kBilinear) {
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
  }
  const auto wx = cubicWeights(fx), wy = cubicWeights(fy);
  double sum = 0.0;
  for (int j = 0; j < 4; ++j) {
    double line = 0.0;
    for (int i = 0; i < 4; ++i) line += wx[std::size_t(i)] * at(x0 - 1 + i, y0 - 1 + j);
    sum += wy[std::size_t(j)] * line;
  }
  return sum;
}

// Samples at(xi, yi) (xi in [0, width), yi in [0, height)) at (x, y).
template <class At>
double sample(const At& at, int width, int height, double x, double y, bool wrapX,
              Interpolation how) {
  using namespace resample_detail;
  y = std::clamp(y, 0.0, double(height - 1));
  if (wrapX) {
    x = std::fmod(x, double(width));  // any finite x (a file's far-off western longitude)
    if (x < 0) x += width;
  } else {
    x = std::clamp(x, 0.0, double(width - 1));
  }
  return sampleUnclamped(
      [&](int xi, int yi) {
        return at(wrapX ? wrapIndex(xi, width) : std::clamp(xi, 0, width - 1),
                  std::clamp(yi, 0, height - 1));
      },
      x, y, how);
}

}  // namespace ps::io
