#include "core/grid.hpp"

#include "core/input_error.hpp"

namespace ps::core {

GridSize::GridSize(int n) : n_(n) {
  if (n < kMinLevel || n > kMaxLevel) {
    throw InputError("grid level n = " + std::to_string(n) +
                     " is out of range: a grid is (2^n+1)^2 with " + std::to_string(kMinLevel) +
                     " <= n <= " + std::to_string(kMaxLevel));
  }
}

GridSize GridSize::fromSide(long long side) {
  const long long m = side - 1;
  if (side < 2 || (m & (m - 1)) != 0) {
    throw InputError("grid side " + std::to_string(side) +
                     " is not 2^n + 1 (e.g. 2049, 4097, 8193)");
  }
  int n = 0;
  while ((1LL << n) < m) ++n;
  return GridSize(n);
}

}  // namespace ps::core
