#pragma once
// Helpers shared by the sand tests (tests/test_sand_*.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/latlong_chart.hpp"
#include "sand/material.hpp"
#include "sand/sand_field.hpp"
#include "sand/sand_grid.hpp"

namespace ps::sandtest {

inline std::shared_ptr<const core::FlatChart> flatChart(int n, double dx = 1.0, double dy = 1.0) {
  return std::make_shared<core::FlatChart>(core::GridSize(n), dx, dy);
}

inline std::shared_ptr<const core::LatLongChart> sphereChart(int n, double R = 6372790.0) {
  return std::make_shared<core::LatLongChart>(core::GridSize(n), R);
}

// Heights from a function of (u, v); on a sphere chart seam twins and pole rows are made one
// point (u = m copies u = 0, a pole row takes its u = 0 value).
inline std::vector<float> heightsFrom(const core::Chart& chart,
                                      const std::function<double(int, int)>& f) {
  const core::GridSize g = chart.grid();
  const int m = g.m();
  std::vector<float> h(g.count());
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) h[g.index(u, v)] = float(f(u, v));
  }
  if (chart.wrapsU()) {
    for (int v = 0; v <= m; ++v) h[g.index(m, v)] = h[g.index(0, v)];
  }
  if (chart.hasPoleRows()) {
    for (int v : {0, m}) {
      for (int u = 0; u <= m; ++u) h[g.index(u, v)] = h[g.index(0, v)];
    }
  }
  return h;
}

// Largest excess (height difference minus the talus threshold) over all 8-neighbour links of the
// current heights of a field, in units of tan(talus) * distance: <= tolerance at rest.
inline double worstTalusExcess(const sand::SandField& f, const sand::Material& mat) {
  const sand::SandGrid& g = f.grid();
  const int m = g.m();
  const double T = mat.tanTalus();
  double worst = -1e300;
  auto link = [&](double a, double b, double dist) {
    const double e = std::abs(a - b) - (T * dist + mat.cohesion);
    worst = std::max(worst, e / (T * dist));
  };
  if (g.glued()) {  // every link of every cell, across the folds
    for (int v = 0; v <= m; ++v) {
      for (int u = 0; u <= m; ++u) {
        if (!g.isCell(u, v)) continue;
        for (int k = 0; k < 8; ++k) {
          const core::GridPoint n = g.neighbour(u, v, k);
          if (n.u >= 0) link(f.height(u, v), f.height(n.u, n.v), g.chord(u, v, k));
        }
      }
    }
    return worst;
  }
  for (int v = 0; v <= m; ++v) {
    if (!g.ordinaryRow(v)) continue;
    for (int u = 0; u < g.columns(); ++u) {
      const double h = f.height(u, v);
      const int ue = g.sphere() ? (u + 1) % m : u + 1;
      if (ue < g.columns()) link(h, f.height(ue, v), g.horizontal(v));
      if (v + 1 <= m) {
        if (g.ordinaryRow(v + 1)) {
          link(h, f.height(u, v + 1), g.vertical(v));
          const int uw = g.sphere() ? (u + m - 1) % m : u - 1;
          if (ue < g.columns()) link(h, f.height(ue, v + 1), g.diagonal(v));
          if (uw >= 0) link(h, f.height(uw, v + 1), g.diagonal(v));
        } else {
          link(h, f.height(0, v + 1), g.vertical(v));  // the north pole
        }
      }
      if (v == 1 && g.sphere()) link(h, f.height(0, 0), g.vertical(0));  // the south pole
    }
  }
  return worst;
}

inline bool allFinite(const sand::SandField& f) {
  std::vector<double> h;
  f.copyHeights(h);
  for (double x : h) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace ps::sandtest
