#include "io/nodata_fill.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ps::io {

FillReport fillHoles(std::vector<float>& v, int w, int h, const std::vector<std::uint8_t>& hole,
                     bool wrapX) {
  const std::size_t n = std::size_t(w) * std::size_t(h);
  if (v.size() != n || hole.size() != n) throw std::invalid_argument("fillHoles: size mismatch");
  FillReport rep;
  std::vector<std::size_t> holes;
  float lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < n; ++i) {
    if (hole[i]) {
      holes.push_back(i);
    } else {
      lo = std::min(lo, v[i]);
      hi = std::max(hi, v[i]);
    }
  }
  rep.filled = holes.size();
  if (holes.empty()) return rep;
  if (holes.size() == n) throw std::invalid_argument("fillHoles: no valid pixel to fill from");

  auto neighbours = [&](std::size_t i, std::size_t out[4]) {
    const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
    int k = 0;
    if (x > 0)
      out[k++] = i - 1;
    else if (wrapX && w > 1)
      out[k++] = i + std::size_t(w - 1);
    if (x + 1 < w)
      out[k++] = i + 1;
    else if (wrapX && w > 1)
      out[k++] = i - std::size_t(w - 1);
    if (y > 0) out[k++] = i - std::size_t(w);
    if (y + 1 < h) out[k++] = i + std::size_t(w);
    return k;
  };

  // Start: each hole pixel takes the value of a nearest valid pixel (breadth-first from the rim).
  std::vector<std::uint8_t> known(hole.size());
  for (std::size_t i = 0; i < n; ++i) known[i] = hole[i] ? 0 : 1;
  std::vector<std::size_t> frontier, next;
  for (const std::size_t i : holes) {
    std::size_t nb[4];
    const int k = neighbours(i, nb);
    for (int j = 0; j < k; ++j) {
      if (!hole[nb[j]]) {
        v[i] = v[nb[j]];
        frontier.push_back(i);
        break;
      }
    }
  }
  for (const std::size_t i : frontier) known[i] = 1;
  while (!frontier.empty()) {
    next.clear();
    for (const std::size_t i : frontier) {
      std::size_t nb[4];
      const int k = neighbours(i, nb);
      for (int j = 0; j < k; ++j) {
        if (!known[nb[j]]) {
          known[nb[j]] = 1;
          v[nb[j]] = v[i];
          next.push_back(nb[j]);
        }
      }
    }
    frontier.swap(next);
  }

  // Successive over-relaxation of the discrete Laplace equation on the hole pixels.
  const double tol = std::max(1e-4 * double(hi - lo), 1e-6);
  const double omega = 1.9;
  const int maxSweeps = 5000;
  for (rep.sweeps = 1; rep.sweeps <= maxSweeps; ++rep.sweeps) {
    double change = 0;
    for (const std::size_t i : holes) {
      std::size_t nb[4];
      const int k = neighbours(i, nb);
      double sum = 0;
      for (int j = 0; j < k; ++j) sum += v[nb[j]];
      const double target = sum / k;
      const double upd = double(v[i]) + omega * (target - double(v[i]));
      const float nv = float(std::clamp(upd, double(lo), double(hi)));
      change = std::max(change, std::abs(double(nv) - double(v[i])));
      v[i] = nv;
    }
    rep.lastChange = change;
    if (change < tol) break;
  }
  rep.sweeps = std::min(rep.sweeps, maxSweeps);
  return rep;
}

}  // namespace ps::io
