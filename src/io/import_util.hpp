#pragma once
// Helpers the heightmap import's files share (heightmap_import.cpp, import_values.cpp,
// import_resample.cpp, import_options.cpp); not part of the io layer's interface.
#include <string>
#include <vector>

#include "core/input_error.hpp"
#include "io/resample.hpp"

namespace ps::io::import_detail {

[[noreturn]] inline void fail(const std::string& name, const std::string& what) {
  throw core::InputError(name + ": " + what);
}

inline int levelFor(long long cells) {
  int n = core::GridSize::kMinLevel;
  while (n < 13 && (1LL << n) < cells) ++n;
  return n;
}

// A sample of image values `v` (w x h) at pixel coordinates (x, y), pixel centres at integers.
inline double sampleImage(const std::vector<float>& v, int w, int h, double x, double y, bool wrapX,
                          Interpolation how) {
  const auto at = [&](int xi, int yi) {
    return double(v[std::size_t(yi) * std::size_t(w) + std::size_t(xi)]);
  };
  return sample(at, w, h, x, y, wrapX, how);
}

}  // namespace ps::io::import_detail
