#pragma once
// Helpers shared by the sand tests (tests/test_sand_*.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/torus_chart.hpp"
#include "sand/material.hpp"
#include "sand/sand_field.hpp"
#include "sand/sand_grid.hpp"
#include "stress_util.hpp"

namespace ps::sandtest {

inline std::shared_ptr<const core::FlatChart> flatChart(int n, double dx = 1.0, double dy = 1.0) {
  return std::make_shared<core::FlatChart>(core::GridSize(n), dx, dy);
}

inline std::shared_ptr<const core::LatLongChart> sphereChart(int n, double R = 6372790.0) {
  return std::make_shared<core::LatLongChart>(core::GridSize(n), R);
}

// Heights from a function of (u, v); on a sphere chart seam twins and pole rows are made one
// point (u = m copies u = 0, a pole row takes its u = 0 value).
// A torus of R = 4 km, r = 1.5 km or a cylinder of radius 2 km, length 8 km (the charts'
// tests' shapes at a thousandth: cells of tens of metres at 2^6).
inline std::shared_ptr<const core::Chart> smallTube(bool torus, int n) {
  if (torus) return std::make_shared<core::TorusChart>(core::GridSize(n), 4000.0, 1500.0);
  return std::make_shared<core::CylinderChart>(core::GridSize(n), 2000.0, 8000.0);
}

inline const char* tubeName(bool torus) {
  return torus ? "torus" : "cylinder";
}

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

// Heights drawn by `draw` at each of the chart's distinct points (in grid order), copied to their
// twins.
inline std::vector<float> twinNoise(const core::Chart& chart, const std::function<double()>& draw) {
  const core::GridSize g = chart.grid();
  std::vector<float> h(g.count(), 0.0f);
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const core::GridPoint c = chart.canonical(u, v);
      if (c.u == u && c.v == v) h[g.index(u, v)] = float(draw());
    }
  }
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      const core::GridPoint c = chart.canonical(u, v);
      h[g.index(u, v)] = h[g.index(c.u, c.v)];
    }
  }
  return h;
}

// The links of every cell of a glued grid: each to another cell, with a chord in (0, maxChord)
// and, on the 4 axis links, a face > 0; an infinite chord where a link is missing;
// `expectedLinks(u, v)` links at cell (u, v); i -> j as often as j -> i, with bitwise the same
// chords and faces. Call it inside ASSERT_NO_FATAL_FAILURE.
inline void checkLinksSymmetric(const sand::SandGrid& g, double maxChord,
                                const std::function<int(int, int)>& expectedLinks,
                                const std::string& what) {
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::pair<double, double>>> links;
  const core::GridSize gs = g.grid();
  const int m = g.m();
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      if (!g.isCell(u, v)) continue;
      int count = 0;
      for (int k = 0; k < 8; ++k) {
        const core::GridPoint nb = g.neighbour(u, v, k);
        if (nb.u < 0) {
          EXPECT_EQ(g.chord(u, v, k), std::numeric_limits<double>::infinity()) << what;
          continue;
        }
        ++count;
        ASSERT_TRUE(g.isCell(nb.u, nb.v)) << what;
        ASSERT_FALSE(nb.u == u && nb.v == v) << what;
        const double d = g.chord(u, v, k);
        ASSERT_GT(d, 0.0) << what;
        ASSERT_LT(d, maxChord) << what;
        const double L = k < 4 ? g.face(u, v, k) : -1.0;
        if (k < 4) {
          ASSERT_GT(L, 0.0) << what;
        }
        links[{gs.index(u, v), gs.index(nb.u, nb.v)}].push_back({d, L});
      }
      EXPECT_EQ(count, expectedLinks(u, v)) << what << " " << u << "," << v;
    }
  }
  for (auto& [key, list] : links) {
    auto back = links.find({key.second, key.first});
    ASSERT_NE(back, links.end()) << what;
    auto a = list, b = back->second;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    ASSERT_EQ(a.size(), b.size()) << what << " " << key.first << " " << key.second;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(a[i])), 0)
          << what << " " << key.first << " " << key.second;
    }
  }
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

// Marks every cell whose height is not 0 (the edit a field is told about).
inline void markNonZero(sand::SandField& f, const core::Chart& chart, std::span<const float> h) {
  const core::GridSize g = chart.grid();
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      if (h[g.index(u, v)] != 0.0f) f.mark({u, u, v, v});
    }
  }
}

// The field's sum over cells of area times |height|: the scale its volume drift is told against.
inline double absVolume(const sand::SandField& f) {
  std::vector<double> h;
  f.copyHeights(h);
  std::vector<float> hf(h.begin(), h.end());
  return f.grid().absVolume(hf);
}

inline bool sameDoubles(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// Every grid vertex takes its canonical point's value (twins equal), as a field's heights are.
template <class T>
void copyFromCanonical(const core::Chart& chart, std::vector<T>& h) {
  const core::GridSize& gs = chart.grid();
  for (int v = 0; v <= gs.m(); ++v) {
    for (int u = 0; u <= gs.m(); ++u) {
      const core::GridPoint c = chart.canonical(u, v);
      h[gs.index(u, v)] = h[gs.index(c.u, c.v)];
    }
  }
}

// The reference checks' field: noise in [0, amplitude) at every cell, or only at the cells
// within 7 cells of `spot` (box: the noisy cells' bounds), twins equal.
struct ReferenceScene {
  std::vector<float> h;
  terrain::VertexBox box;
};
inline ReferenceScene referenceScene(const sand::SandGrid& g, core::GridPoint spot,
                                     double amplitude, bool everywhere, unsigned seed) {
  const core::GridSize& gs = g.grid();
  const int m = g.m();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(0.0, amplitude);
  const Eigen::Vector3d c = g.point(spot.u, spot.v);
  const double radius = 7.0 * g.chord(spot.u, spot.v, 1);
  std::vector<float> h(gs.count(), 0.0f);
  int u0 = m, u1 = 0, v0 = m, v1 = 0;
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      if (!g.isCell(u, v)) continue;
      if (!everywhere && (g.point(u, v) - c).norm() > radius) continue;
      h[gs.index(u, v)] = float(noise(rng));
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
  }
  copyFromCanonical(g.chart(), h);
  return {std::move(h), {u0, u1, v0, v1}};
}

// One thermal step of docs/SAND.md's rule ("Thermal erosion") on a glued chart, cell by cell from
// SandGrid's links, chords and areas: the reference the tiled kernels must equal bit for bit (the
// same operations in the same order; a missing link adds nothing). h holds every grid vertex,
// twins equal; so does the result.
inline void thermalReferenceStep(const sand::SandGrid& g, std::vector<double>& h,
                                 const sand::Material& mat) {
  const core::GridSize& gs = g.grid();
  const int m = g.m();
  const double T = mat.tanTalus(), coh = mat.cohesion, eta = mat.talusTolerance;
  const double halfRate = 0.5 * mat.erosionRate;
  auto act = [](double e, double eps) { return e > eps ? e : 0.0; };
  auto cap = [&](int u, int v) {
    return g.cellArea(u, v) * (g.linkCount(u, v) == 4 ? 0.25 : 0.125);
  };
  std::vector<double> s(gs.count(), 0.0), next = h;
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      if (!g.isCell(u, v)) continue;
      const double hi = h[gs.index(u, v)];
      double e[8];
      for (int k = 0; k < 8; ++k) {
        const core::GridPoint n = g.neighbour(u, v, k);
        const double d = g.chord(u, v, k);
        e[k] = n.u < 0 ? 0.0 : act(hi - h[gs.index(n.u, n.v)] - (T * d + coh), eta * T * d);
      }
      const double E = ((e[0] + e[1]) + (e[2] + e[3])) + ((e[4] + e[7]) + (e[5] + e[6]));
      const double mx = std::max(std::max(std::max(e[0], e[1]), std::max(e[2], e[3])),
                                 std::max(std::max(e[4], e[7]), std::max(e[5], e[6])));
      s[gs.index(u, v)] = E > 0.0 ? (halfRate * g.cellArea(u, v)) * mx / E : 0.0;
    }
  }
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      if (!g.isCell(u, v)) continue;
      const std::size_t i = gs.index(u, v);
      double f[8];
      for (int k = 0; k < 8; ++k) {
        const core::GridPoint n = g.neighbour(u, v, k);
        f[k] = 0.0;
        if (n.u < 0) continue;
        const std::size_t j = gs.index(n.u, n.v);
        const double dist = g.chord(u, v, k), d = h[i] - h[j];
        const double a = act(std::abs(d) - (T * dist + coh), eta * T * dist);
        const double coef = d > 0.0 ? -std::min(s[i], cap(n.u, n.v)) : std::min(s[j], cap(u, v));
        f[k] = coef * a;
      }
      const double net = ((f[0] + f[1]) + (f[2] + f[3])) + ((f[4] + f[7]) + (f[5] + f[6]));
      next[i] = h[i] + net * (1.0 / g.cellArea(u, v));
    }
  }
  copyFromCanonical(g.chart(), next);
  h.swap(next);
}

// Thermal steps on a glued chart's field against thermalReferenceStep, bit for bit after each:
// noise everywhere (every tile in P), then noise in a disc about `spot` (radius 7 cells) with only
// its box marked (P's edges: walls in the tiles' halos).
inline void checkThermalAgainstReference(std::shared_ptr<const core::Chart> chart,
                                         core::GridPoint spot, double amplitude, int steps,
                                         const std::string& what) {
  const sand::SandGrid g(chart);
  const sand::Material mat = sand::Material::sand();
  for (const bool everywhere : {true, false}) {
    ReferenceScene scene = referenceScene(g, spot, amplitude, everywhere, everywhere ? 11 : 12);
    std::vector<double> ref(scene.h.begin(), scene.h.end()), got;
    sand::SandField f(chart, scene.h);
    if (everywhere) {
      f.markAll();
    } else {
      f.mark(scene.box);
    }
    for (int step = 0; step < steps; ++step) {
      f.thermalStep(mat);
      thermalReferenceStep(g, ref, mat);
      f.copyHeights(got);
      ASSERT_TRUE(sameDoubles(got, ref))
          << what << (everywhere ? ", noise everywhere" : ", a disc marked") << ", step " << step;
    }
  }
}

// Runs thermal steps until rest (or maxSteps); returns the steps run.
inline int settle(sand::SandField& f, const sand::Material& mat, int maxSteps) {
  int steps = 0;
  while (!f.atRest() && steps < maxSteps) {
    f.thermalStep(mat);
    ++steps;
  }
  return steps;
}

// Steps `a` (the cells marked in it) and `b` (every cell, marked before each step) `steps`
// thermal steps side by side: a visits no more cells than b, and at every 25th step and the last
// both hold the same heights bit for bit. Call it inside ASSERT_NO_FATAL_FAILURE.
inline void thermalSideBySide(sand::SandField& a, sand::SandField& b, const sand::Material& mat,
                              int steps, const std::string& what) {
  std::vector<double> ha, hb;
  for (int step = 0; step < steps; ++step) {
    b.markAll();
    const auto ra = a.thermalStep(mat);
    const auto rb = b.thermalStep(mat);
    ASSERT_LE(ra.cells, rb.cells) << what << " step " << step;
    if (step % 25 == 0 || step == steps - 1) {
      a.copyHeights(ha);
      b.copyHeights(hb);
      ASSERT_TRUE(sameDoubles(ha, hb)) << what << " step " << step;
    }
  }
}

// Steps `a` (the cells marked in it) and `b` (every cell, marked before each step) `steps`
// diffusion steps side by side; true when they then hold the same heights bit for bit.
inline bool diffusionSideBySide(sand::SandField& a, sand::SandField& b, const sand::Material& mat,
                                double dt, sand::DiffusionScheme scheme, sand::StepPolicy policy,
                                int steps, const sand::PushForce* force = nullptr) {
  for (int step = 0; step < steps; ++step) {
    b.markAll();
    a.diffusionStep(mat, dt, scheme, policy, force);
    b.diffusionStep(mat, dt, scheme, policy, force);
  }
  std::vector<double> ha, hb;
  a.copyHeights(ha);
  b.copyHeights(hb);
  return sameDoubles(ha, hb);
}

// Success when every height of the field is finite and within [lo, hi]; else the first that is
// not.
inline ::testing::AssertionResult heightsWithin(const sand::SandField& f, double lo, double hi) {
  std::vector<double> x;
  f.copyHeights(x);
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || x[i] < lo || x[i] > hi) {
      return ::testing::AssertionFailure()
             << "height " << i << " is " << x[i] << ", outside [" << lo << ", " << hi << "]";
    }
  }
  return ::testing::AssertionSuccess();
}

// The largest volume drift and the most steps to rest of the piles settled by settlePile.
struct SettleFigures {
  double worstDrift = 0.0;
  int mostSteps = 0;
};

// A pile or crater (heights h, 0 off it) settled by thermal steps from its marked cells: the
// first 150 beside a field stepping every cell (thermalSideBySide), then to rest: finite, at the
// talus, its volume kept to 1e-13 after 150 steps and 1e-12 at rest. `atRest` sees the settled
// field; then it is written back into h. Call it inside ASSERT_NO_FATAL_FAILURE.
inline void settlePile(const std::shared_ptr<const core::Chart>& chart, std::vector<float>& h,
                       const sand::Material& mat, const std::string& what, SettleFigures& figures,
                       const std::function<void(const sand::SandField&)>& atRest = {}) {
  auto h2 = h;
  sand::SandField a(chart, h), b(chart, h2);
  markNonZero(a, *chart, h);
  const double v0 = a.volume(), scale = absVolume(a);
  ASSERT_NO_FATAL_FAILURE(thermalSideBySide(a, b, mat, 150, what));
  EXPECT_TRUE(allFinite(a)) << what;
  EXPECT_LE(std::abs(a.volume() - v0) / scale, 1e-13) << what;
  const int more = settle(a, mat, 20000);
  EXPECT_TRUE(a.atRest()) << what;
  EXPECT_LE(worstTalusExcess(a, mat), mat.talusTolerance * (1 + 1e-9)) << what;
  EXPECT_LE(std::abs(a.volume() - v0) / scale, 1e-12) << what;
  figures.worstDrift = std::max(figures.worstDrift, std::abs(a.volume() - v0) / scale);
  figures.mostSteps = std::max(figures.mostSteps, 150 + more);
  if (atRest) atRest(a);
  a.writeBack(1e30);
}

// Marks every cell of f and checks that an explicit step of twice the bound is refused; returns
// the bound.
inline double refusesTwiceTheExplicitBound(sand::SandField& f, const sand::Material& mat) {
  f.markAll();
  const double bound = f.explicitBound(mat);
  EXPECT_THROW(
      f.diffusionStep(mat, 2 * bound, sand::DiffusionScheme::kExplicit, sand::StepPolicy::kRefuse),
      core::InputError);
  return bound;
}

// A push force on a flat layer 10 m deep (planet frame: the tool at grid point `at`, 10 m up).
struct PushCase {
  core::GridPoint at;
  double radius = 0.0;  // m
  sand::DiffusionScheme scheme = sand::DiffusionScheme::kExplicit;
  double dt = 0.2;           // s
  double boundFactor = 0.0;  // > 0: dt is this many explicit bounds instead
  int steps = 20;
  double volumeTolerance = 1e-13;  // relative
};

// The layer pushed from its marked tiles and from every tile side by side: the same bit for bit,
// finite, its volume kept, a rut of more than 0.5 m under the tool. `check` then sees both
// fields (marked, whole).
inline void pushTheLayer(
    const std::shared_ptr<const core::Chart>& chart, const PushCase& c, const std::string& what,
    const std::function<void(const sand::SandField&, const sand::SandField&)>& check) {
  const sand::Material mat = sand::Material::sand();
  std::vector<float> h(chart->grid().count(), 10.0f), h2 = h;
  sand::SandField a(chart, h), b(chart, h2);
  const double v0 = a.volume();
  const sand::PushForce force{chart->position(c.at.u, c.at.v, 10.0), c.radius, 2e4};
  const double dt = c.boundFactor > 0.0 ? c.boundFactor * a.explicitBound(mat) : c.dt;
  EXPECT_TRUE(
      diffusionSideBySide(a, b, mat, dt, c.scheme, sand::StepPolicy::kClamp, c.steps, &force))
      << what;
  EXPECT_TRUE(allFinite(a)) << what;
  EXPECT_LE(std::abs(a.volume() - v0) / v0, c.volumeTolerance) << what;
  EXPECT_LT(a.height(c.at.u, c.at.v), 10.0 - 0.5) << what;  // the rut under the tool
  check(a, b);
}

// A 300 m deep crater (heights 0 or -300 in h, its cells marked from them) diffused 60 explicit
// steps at the bound from its marked cells and from the whole grid: the same bit for bit, finite,
// its volume kept to 1e-13, the range not grown (the maximum principle), the wall moved.
inline void explicitCraterDiffuses(const std::shared_ptr<const core::Chart>& chart,
                                   std::vector<float> h, const sand::Material& mat,
                                   const std::string& what) {
  auto h2 = h;
  sand::SandField a(chart, h), b(chart, h2);
  markNonZero(a, *chart, h);
  const double v0 = a.volume(), scale = absVolume(a);
  const double dt = a.explicitBound(mat);
  ASSERT_TRUE(std::isfinite(dt) && dt > 0.0) << what;
  EXPECT_TRUE(diffusionSideBySide(a, b, mat, dt, sand::DiffusionScheme::kExplicit,
                                  sand::StepPolicy::kRefuse, 60))
      << what;
  EXPECT_TRUE(allFinite(a)) << what;
  EXPECT_LE(std::abs(a.volume() - v0) / scale, 1e-13) << what;
  std::vector<double> ha;
  a.copyHeights(ha);
  double lo = 1e300, hi = -1e300;
  int between = 0;
  for (double x : ha) {
    lo = std::min(lo, x), hi = std::max(hi, x);
    between += (x > -300.0 && x < 0.0) ? 1 : 0;
  }
  EXPECT_GE(lo, -300.0) << what;
  EXPECT_LE(hi, 0.0) << what;
  EXPECT_GT(between, 0) << what;
}

// 1e5 steps (times the stress scale) of `step` on a flat 33^2 field of noise in +-amplitude
// (every cell marked), kicked every 25000 steps by a spike within the initial range: success
// when the heights then are finite and within that range (the step obeys a maximum principle).
inline ::testing::AssertionResult kickedNoiseKeepsItsRange(
    unsigned seed, double amplitude, const std::function<void(sand::SandField&)>& step) {
  auto chart = flatChart(5);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-amplitude, amplitude);
  auto h = heightsFrom(*chart, [&](int, int) { return noise(rng); });
  const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  const double lo0 = *lo, hi0 = *hi;
  sand::SandField f(chart, h);
  f.markAll();
  for (int i = 0; i < 100000 * testkit::stressScale(); ++i) {
    if (i % 25000 == 24999) {  // a spike somewhere (within the initial range)
      f.writeBack(1e30);
      const int u = int(rng() % 33), v = int(rng() % 33);
      h[chart->grid().index(u, v)] = float(0.01 * noise(rng));
      f.mark({u, u, v, v});
    }
    step(f);
  }
  return heightsWithin(f, lo0 - 1e-6, hi0 + 1e-6);
}

}  // namespace ps::sandtest
