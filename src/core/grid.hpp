#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace ps::core {

// A (2^n+1) x (2^n+1) vertex grid. u runs along a row (longitude on the lat-long chart), v along
// a column (latitude). Storage is row-major: index = v * side + u.
class GridSize {
 public:
  static constexpr int kMinLevel = 5;
  static constexpr int kMaxLevel = 15;

  // Throws InputError unless kMinLevel <= n <= kMaxLevel.
  explicit GridSize(int n);
  // Throws InputError unless side == 2^n + 1 with n in range.
  static GridSize fromSide(long long side);

  int n() const { return n_; }
  int m() const { return 1 << n_; }  // cells per side
  int side() const { return m() + 1; }
  std::size_t count() const { return std::size_t(side()) * std::size_t(side()); }
  std::size_t index(int u, int v) const {
    return std::size_t(v) * std::size_t(side()) + std::size_t(u);
  }
  std::string label() const { return std::to_string(side()) + "x" + std::to_string(side()); }

 private:
  int n_;
};

// Integer grid point.
struct GridPoint {
  int u = 0;
  int v = 0;
  friend bool operator==(const GridPoint&, const GridPoint&) = default;
};

}  // namespace ps::core
