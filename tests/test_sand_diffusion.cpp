#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "core/input_error.hpp"
#include "sand/kernels.hpp"
#include "sand/sand_field.hpp"
#include "test_sand_util.hpp"

using namespace ps;
using sand::DiffusionScheme;
using sand::StepPolicy;
using sandtest::flatChart;
using sandtest::heightsFrom;
using sandtest::sphereChart;

namespace {

double amplitude(const sand::SandField& f) {
  std::vector<double> h;
  f.copyHeights(h);
  double a = 0;
  for (double x : h) a = std::max(a, std::abs(x));
  return a;
}

// Largest face angle (degrees) over the 4-neighbour faces, minus the angle of repose.
double worstReposeExcessDeg(const sand::SandField& f, const sand::Material& mat) {
  const sand::SandGrid& g = f.grid();
  const int m = g.m();
  double worst = -90;
  auto face = [&](double a, double b, double dist) {
    const double s = std::max(std::abs(a - b) - mat.cohesion, 0.0) / dist;
    worst = std::max(worst, std::atan(s) * 180.0 / std::numbers::pi - mat.reposeDeg);
  };
  for (int v = 0; v <= m; ++v) {
    if (!g.ordinaryRow(v)) continue;
    for (int u = 0; u < g.columns(); ++u) {
      const int ue = g.sphere() ? (u + 1) % m : u + 1;
      if (ue < g.columns()) face(f.height(u, v), f.height(ue, v), g.horizontal(v));
      if (v < m) face(f.height(u, v), f.height(g.ordinaryRow(v + 1) ? u : 0, v + 1), g.vertical(v));
      if (v == 1 && g.sphere()) face(f.height(u, v), f.height(0, 0), g.vertical(0));
    }
  }
  return worst;
}

}  // namespace

TEST(SandKernels, FastArctangentIsWithin3e8Radians) {
  double worst = 0;
  for (double x = 0; x < 50; x += 0.001)
    worst = std::max(worst, std::abs(sand::kernels::fastAtan(x) - std::atan(x)));
  for (double x : {1e-300, 1e-8, 1.0, 1e8, 1e300}) {
    worst = std::max(worst, std::abs(sand::kernels::fastAtan(x) - std::atan(x)));
  }
  EXPECT_LT(worst, 3e-8);
}

TEST(SandKernels, RowSolverMatchesADenseSolveIncludingTheCircle) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(0.0, 3.0);
  for (int n : {1, 2, 3, 7, 40}) {
    for (bool circle : {false, true}) {
      std::vector<double> k(std::size_t(n), 0.0), b(std::size_t(n), 0.0);
      for (auto& x : k) x = uni(rng);
      for (auto& x : b) x = uni(rng) - 1.0;
      if (circle && n < 3) continue;
      // Dense matrix.
      const int faces = circle ? n : n - 1;
      std::vector<double> A(std::size_t(n * n), 0.0);
      for (int i = 0; i < n; ++i) A[std::size_t(i * n + i)] = 1.0;
      for (int f = 0; f < faces; ++f) {
        const int i = f, j = (f + 1) % n;
        const double kk = k[std::size_t(f)];
        A[std::size_t(i * n + i)] += kk;
        A[std::size_t(j * n + j)] += kk;
        A[std::size_t(i * n + j)] -= kk;
        A[std::size_t(j * n + i)] -= kk;
      }
      std::vector<double> x = b, work;
      sand::kernels::solveRow(x, k, circle, work);
      double sumB = 0, sumX = 0;
      for (int i = 0; i < n; ++i) {
        double r = -b[std::size_t(i)];
        for (int j = 0; j < n; ++j) r += A[std::size_t(i * n + j)] * x[std::size_t(j)];
        EXPECT_NEAR(r, 0.0, 1e-12) << "n " << n << " circle " << circle << " row " << i;
        sumB += b[std::size_t(i)];
        sumX += x[std::size_t(i)];
      }
      EXPECT_NEAR(sumX, sumB, 1e-12);
    }
  }
}

// The glued lines' kernels against the forms they replace, bit for bit: lineWeights (a loop the
// compiler vectorises) against weight() face by face, solveChainInPlace against solveLine's open
// chain (which copies), on random lines with faces at rest, some cohesion and steep and flat
// faces.
TEST(SandKernels, LineWeightsAndChainsInPlaceEqualTheOneAtATimeFormsBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  sand::Material mat = sand::Material::sand();
  mat.cohesion = 0.05;
  const sand::kernels::Repose rep = sand::kernels::Repose::of(mat);
  int active = 0, rest = 0;
  for (int n : {2, 3, 5, 33, 200}) {
    for (bool circle : {false, true}) {
      const std::size_t len = std::size_t(n);
      std::vector<double> h(len), ratio(len), inv(len);
      for (int i = 0; i < n; ++i) {
        h[std::size_t(i)] = 10.0 * uni(rng) * (uni(rng) < 0.3 ? 0.01 : 1.0);
        ratio[std::size_t(i)] = 0.5 + uni(rng);
        inv[std::size_t(i)] = 0.2 + 2.0 * uni(rng);
      }
      const double dt = 0.7, Dl2 = 1.3;
      std::vector<double> w(len, -1.0), k(len, -1.0);
      sand::kernels::lineWeights(h.data(), ratio.data(), inv.data(), w.data(), k.data(), n, circle,
                                 dt, Dl2, rep);
      const int faces = circle ? n : n - 1;
      for (int p = 0; p < faces; ++p) {
        const std::size_t i = std::size_t(p), j = std::size_t((p + 1) % n);
        const double wp = sand::kernels::weight(std::abs(h[i] - h[j]), inv[i], rep);
        EXPECT_EQ(std::memcmp(&w[i], &wp, sizeof wp), 0) << "n " << n << " face " << p;
        const double kp = dt * (Dl2 * ratio[i]) * wp;
        EXPECT_EQ(std::memcmp(&k[i], &kp, sizeof kp), 0) << "n " << n << " face " << p;
        (wp > 0.0 ? active : rest) += 1;
      }
      if (!circle) {
        EXPECT_EQ(w[std::size_t(n - 1)], -1.0) << "n " << n << ": no face there";
      }
      // An open chain with every face active.
      std::vector<double> x(len), a(len), K(len);
      for (int i = 0; i < n; ++i) {
        x[std::size_t(i)] = 100.0 * uni(rng) - 50.0;
        a[std::size_t(i)] = 0.5 + uni(rng);
        K[std::size_t(i)] = 1e-3 + 30.0 * uni(rng);
      }
      std::vector<double> ref = x, work, cp(len);
      sand::kernels::solveLine(ref, a, K, false, work);
      sand::kernels::solveChainInPlace(x.data(), a.data(), K.data(), n, cp.data());
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(std::memcmp(&x[std::size_t(i)], &ref[std::size_t(i)], sizeof(double)), 0)
            << "n " << n << " cell " << i << ": " << x[std::size_t(i)] << " vs "
            << ref[std::size_t(i)];
      }
    }
  }
  EXPECT_GT(active, 50);  // both kinds of face were checked
  EXPECT_GT(rest, 20);
}

TEST(SandDiffusion, ExplicitBoundIsAQuarterOverDOnASquareGrid) {
  auto chart = flatChart(5, 3.0, 3.0);
  std::vector<float> h(chart->grid().count(), 0.0f);
  sand::SandField f(chart, h);
  EXPECT_DOUBLE_EQ(f.explicitBound(sand::Material::sand()), 0.25);  // D = 1
  EXPECT_DOUBLE_EQ(f.explicitBound(sand::Material::mud()), 1.0);    // D = 0.25
  sand::Material still = sand::Material::sand();
  still.diffusion = 0.0;
  EXPECT_TRUE(std::isinf(f.explicitBound(still)));
  // On the sphere the bound is set by the ring next to a pole: about 2 (pi/m)^2 / D.
  auto sphere = sphereChart(6);
  std::vector<float> hs(sphere->grid().count(), 0.0f);
  sand::SandField fs(sphere, hs);
  const double b = fs.explicitBound(sand::Material::sand());
  EXPECT_GT(b, 0.5 * 2 * std::pow(std::numbers::pi / 64, 2));
  EXPECT_LT(b, 2.0 * 2 * std::pow(std::numbers::pi / 64, 2));
}

TEST(StressSand, ExplicitDiffusionRefusesOrClampsAStepPastItsBoundAndBlowsUpPastIt) {
  auto chart = flatChart(5);
  // A checkerboard of +-10 m on 1 m cells: every face far steeper than the angle of repose.
  auto make = [&] {
    return heightsFrom(*chart, [](int u, int v) { return ((u + v) & 1) ? 10.0 : -10.0; });
  };
  const sand::Material mat = sand::Material::sand();
  {
    auto h = make();
    sand::SandField f(chart, h);
    f.markAll();
    const double bound = f.explicitBound(mat);
    try {
      f.diffusionStep(mat, 1.01 * bound, DiffusionScheme::kExplicit, StepPolicy::kRefuse);
      ADD_FAILURE() << "step past the bound accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("dt"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bound"), std::string::npos) << e.what();
    }
    EXPECT_EQ(f.height(3, 4), 10.0);  // refused before anything moved
    const sand::StepReport r =
        f.diffusionStep(mat, 10.0, DiffusionScheme::kExplicit, StepPolicy::kClamp);
    EXPECT_EQ(r.dt, bound);
  }
  // At the bound the checkerboard decays; 1.5 times past it, it grows without limit.
  for (double factor : {1.0, 1.5}) {
    auto h = make();
    sand::SandField f(chart, h);
    f.markAll();
    const double dt = factor * f.explicitBound(mat);
    for (int i = 0; i < 60; ++i)
      f.diffusionStep(mat, dt, DiffusionScheme::kExplicit, StepPolicy::kUnchecked);
    if (factor == 1.0) {
      EXPECT_LE(amplitude(f), 10.0) << "at the bound";
    } else {
      EXPECT_GT(amplitude(f), 1e6) << "past the bound";
    }
  }
}

TEST(SandDiffusion, BothSchemesKeepVolumeOnFlatAndSphereAndSettleToTheAngleOfRepose) {
  for (bool sphere : {false, true}) {
    for (DiffusionScheme scheme : {DiffusionScheme::kExplicit, DiffusionScheme::kSemiImplicit}) {
      std::shared_ptr<const core::Chart> chart =
          sphere ? std::shared_ptr<const core::Chart>(sphereChart(5, 1000.0)) : flatChart(5);
      const int m = chart->grid().m();
      std::mt19937 rng(9);
      std::uniform_real_distribution<double> noise(0.0, sphere ? 300.0 : 6.0);
      auto h = heightsFrom(*chart, [&](int, int v) {
        double x = 50.0 + noise(rng);
        if (sphere && v == m) x += 500.0;  // a spike on the pole
        return x;
      });
      sand::SandField f(chart, h);
      const double scale = sand::SandGrid(chart).absVolume(h);
      const sand::Material mat = sand::Material::sand();
      f.markAll();
      const double v0 = f.volume();
      const double dt = scheme == DiffusionScheme::kExplicit ? 1e9 : 5.0;  // explicit: clamped
      int steps = 0;
      while (!f.atRest() && steps < 20000) {
        f.diffusionStep(mat, dt, scheme);
        ++steps;
      }
      const std::string what =
          std::string(sphere ? "sphere " : "flat ") +
          (scheme == DiffusionScheme::kExplicit ? "explicit" : "semi-implicit");
      EXPECT_TRUE(f.atRest()) << what << " after " << steps;
      EXPECT_LE(std::abs(f.volume() - v0) / scale, 1e-12) << what;
      // At rest every face's weight is within the tolerance: angle <= alpha + tol (90 - alpha).
      EXPECT_LE(worstReposeExcessDeg(f, mat), mat.reposeTolerance * (90.0 - mat.reposeDeg) + 1e-6)
          << what;
      EXPECT_TRUE(sandtest::allFinite(f)) << what;
    }
  }
}

TEST(StressSand, SemiImplicitDiffusionIsStableAtAnyStepAndKeepsTheRange) {
  auto chart = sphereChart(5, 1000.0);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> noise(-1e4, 1e4);
  auto h = heightsFrom(*chart, [&](int, int) { return noise(rng); });
  const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  const double lo0 = *lo, hi0 = *hi;
  sand::SandField f(chart, h);
  const double scale = sand::SandGrid(chart).absVolume(h);
  f.markAll();
  const double v0 = f.volume();
  for (double dt : {1e-3, 1.0, 1e3, 1e6, 1e12}) {
    for (int i = 0; i < 20; ++i)
      f.diffusionStep(sand::Material::pebbles(), dt, DiffusionScheme::kSemiImplicit);
  }
  ASSERT_TRUE(sandtest::heightsWithin(f, lo0 - 1e-6, hi0 + 1e-6));
  EXPECT_LE(std::abs(f.volume() - v0) / scale, 1e-12);
}

TEST(StressSand, DiffusionNoNaNAfter1e5ExplicitStepsAtTheBound) {
  const sand::Material mat = sand::Material::mud();
  double dt = -1.0;  // the bound, taken on the first step (every cell marked, as it was made)
  EXPECT_TRUE(sandtest::kickedNoiseKeepsItsRange(4, 1e5, [&](sand::SandField& f) {
    if (dt < 0.0) dt = f.explicitBound(mat);
    f.diffusionStep(mat, dt, DiffusionScheme::kExplicit, StepPolicy::kRefuse);
  }));
}

TEST(SandDiffusion, ActiveSetStepEqualsWholeGridStepBitForBit) {
  for (DiffusionScheme scheme : {DiffusionScheme::kExplicit, DiffusionScheme::kSemiImplicit}) {
    for (bool sphere : {false, true}) {
      std::shared_ptr<const core::Chart> chart =
          sphere ? std::shared_ptr<const core::Chart>(sphereChart(6, 1000.0)) : flatChart(6);
      const int m = chart->grid().m();
      const int cu = sphere ? 0 : 40, cv = sphere ? 3 : 30;
      auto h = heightsFrom(*chart, [&](int u, int v) {
        const int du = std::min(std::abs(u - cu), m - std::abs(u - cu));
        return (du * du + (v - cv) * (v - cv) <= 9) ? -300.0 : 0.0;
      });
      auto h2 = h;
      sand::SandField a(chart, h), b(chart, h2);
      const sand::Material mat = sand::Material::sand();
      a.mark({cu - 4, cu + 4, 0, cv + 4});
      const double dt = scheme == DiffusionScheme::kExplicit ? a.explicitBound(mat) : 2.0;
      EXPECT_TRUE(sandtest::diffusionSideBySide(a, b, mat, dt, scheme, StepPolicy::kRefuse, 60))
          << "sphere " << sphere << " scheme " << int(scheme);
    }
  }
}

TEST(SandDiffusion, APushForceDigsARutWithBermsAndKeepsVolume) {
  for (DiffusionScheme scheme : {DiffusionScheme::kExplicit, DiffusionScheme::kSemiImplicit}) {
    auto chart = flatChart(6);
    std::vector<float> h(chart->grid().count(), 10.0f);
    sand::SandField f(chart, h);
    const sand::Material mat = sand::Material::sand();
    const double v0 = f.volume();
    sand::PushForce force{{32.0, 32.0, 10.0}, 6.0, 2e4};
    for (int i = 0; i < 20; ++i) f.diffusionStep(mat, 0.2, scheme, StepPolicy::kRefuse, &force);
    EXPECT_LT(f.height(32, 32), 10.0 - 1.0);  // the rut under the tool
    EXPECT_LT(f.height(33, 32), 10.0);
    double berm = 0;
    for (int u = 34; u < 40; ++u) berm = std::max(berm, f.height(u, 32));
    EXPECT_GT(berm, 10.0 + 0.2);                    // the berm around it
    EXPECT_EQ(f.height(45, 32), 10.0);              // beyond the force: untouched
    EXPECT_EQ(f.height(29, 32), f.height(35, 32));  // symmetric about the axis
    EXPECT_EQ(f.height(32, 29), f.height(32, 35));
    EXPECT_LE(std::abs(f.volume() - v0) / v0, 1e-13);
  }
}

TEST(SandDiffusion, BadInputIsRefusedNamingTheParameter) {
  auto chart = flatChart(5);
  std::vector<float> h(chart->grid().count(), 1.0f);
  sand::SandField f(chart, h);
  f.markAll();
  auto expectError = [&](const sand::Material& mat, double dt, const char* word) {
    try {
      f.diffusionStep(mat, dt, DiffusionScheme::kExplicit);
      ADD_FAILURE() << word << " accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  sand::Material m = sand::Material::sand();
  m.diffusion = -1.0;
  expectError(m, 0.1, "diffusion D");
  m = sand::Material::sand();
  m.frictionInverse = -4e-4;
  expectError(m, 0.1, "zeta");
  m = sand::Material::sand();
  m.reposeDeg = 90.0;
  expectError(m, 0.1, "repose");
  expectError(sand::Material::sand(), -1.0, "dt");
  expectError(sand::Material::sand(), std::nan(""), "dt");
  EXPECT_EQ(f.pendingTiles(), 4u);
}
