#pragma once
// The explicit drift-diffusion step on a glued chart against a reference written cell by cell
// from SandGrid's links, chords, faces and areas (tests/test_sand_octahedral.cpp,
// tests/test_sand_tubes.cpp): the tiled kernels, which weigh each face once where they can
// (docs/SAND.md, "Each face weighed once"), must equal it bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sand/kernels.hpp"
#include "sand/material.hpp"
#include "sand/sand_field.hpp"
#include "sand/sand_grid.hpp"
#include "test_sand_util.hpp"

namespace ps::sandtest {

// One explicit step of docs/SAND.md's rule ("Drift-diffusion") of length dt, each cell's four
// face fluxes (D l^2 L / d) w (h_i - h_j) in the order W E S N, summed (W + E) + (S + N); a
// missing link adds nothing. h holds every grid vertex, twins equal; so does the result.
inline void explicitReferenceStep(const sand::SandGrid& g, std::vector<double>& h,
                                  const sand::Material& mat, double dt) {
  const core::GridSize& gs = g.grid();
  const int m = g.m();
  const double Dl2 = mat.diffusion * g.cellSize() * g.cellSize();
  const sand::kernels::Repose repose = sand::kernels::Repose::of(mat);
  std::vector<double> next = h;
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      if (!g.isCell(u, v)) continue;
      const std::size_t i = gs.index(u, v);
      double f[4];
      for (int k = 0; k < 4; ++k) {
        const core::GridPoint n = g.neighbour(u, v, k);
        f[k] = 0.0;
        if (n.u < 0) continue;
        const double dist = g.chord(u, v, k), d = h[i] - h[gs.index(n.u, n.v)];
        const double conductance = Dl2 * (g.face(u, v, k) / dist);
        f[k] = conductance * sand::kernels::weight(std::abs(d), 1.0 / dist, repose) * d;
      }
      const double net = (f[0] + f[1]) + (f[2] + f[3]);
      next[i] = h[i] - (dt * (1.0 / g.cellArea(u, v))) * net;
    }
  }
  copyFromCanonical(g.chart(), next);
  h.swap(next);
}

// Explicit steps at the bound on a glued chart's field against explicitReferenceStep, bit for
// bit after each: noise everywhere (every tile in P), then noise in a disc about `spot` (radius
// 7 cells) with only its box marked (P's edges: walls in the tiles' halos).
inline void checkExplicitAgainstReference(std::shared_ptr<const core::Chart> chart,
                                          core::GridPoint spot, double amplitude, int steps,
                                          const std::string& what) {
  const sand::SandGrid g(chart);
  const sand::Material mat = sand::Material::sand();
  for (const bool everywhere : {true, false}) {
    ReferenceScene scene = referenceScene(g, spot, amplitude, everywhere, everywhere ? 21 : 22);
    std::vector<double> ref(scene.h.begin(), scene.h.end()), got;
    sand::SandField f(chart, scene.h);
    const double bound = f.explicitBound(mat);
    if (everywhere) {
      f.markAll();
    } else {
      f.mark(scene.box);
    }
    for (int step = 0; step < steps; ++step) {
      const sand::StepReport rep = f.diffusionStep(mat, bound, sand::DiffusionScheme::kExplicit);
      ASSERT_GT(rep.cells, 0u) << what << ", step " << step;
      explicitReferenceStep(g, ref, mat, rep.dt);
      f.copyHeights(got);
      ASSERT_TRUE(sameDoubles(got, ref))
          << what << (everywhere ? ", noise everywhere" : ", a disc marked") << ", step " << step;
    }
  }
}

}  // namespace ps::sandtest
