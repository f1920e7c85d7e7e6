#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "terrain/relief.hpp"

#include <omp.h>

using ps::core::Chart;
using ps::core::GridSize;
using ps::core::InputError;
using ps::core::LatLongChart;
using ps::terrain::generateRelief;
using ps::terrain::reliefAt;
using ps::terrain::reliefOctaves;
using ps::terrain::ReliefParams;

namespace {

constexpr double kRadius = 6371000.0;

bool sameBits(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

std::size_t countDifferentBits(const std::vector<float>& a, const std::vector<float>& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += sameBits(a[i], b[i]) ? 0 : 1;
  return n;
}

// A chart that is not a LatLongChart (so generateRelief takes its generic per-vertex path) but
// has the same geometry.
class WrappedChart final : public Chart {
 public:
  explicit WrappedChart(const LatLongChart& inner) : Chart(inner.grid()), inner_(inner) {}
  std::string name() const override { return "wrapped"; }
  Eigen::Vector3d position(int u, int v, double h) const override {
    return inner_.position(u, v, h);
  }
  Eigen::Vector3d up(int u, int v) const override { return inner_.up(u, v); }
  Eigen::Vector3d positionAt(double u, double v, double h) const override {
    return inner_.positionAt(u, v, h);
  }
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override {
    return inner_.inverse(p);
  }
  bool wrapsU() const override { return true; }
  bool hasPoleRows() const override { return true; }
  double sphereRadius() const override { return inner_.sphereRadius(); }

 private:
  const LatLongChart& inner_;
};

}  // namespace

TEST(Relief, IsDeterministicAndSeedDependent) {
  const LatLongChart chart(GridSize(8), kRadius);
  ReliefParams p;
  p.seed = 42;
  const std::vector<float> a = generateRelief(chart, p);
  const std::vector<float> b = generateRelief(chart, p);
  ASSERT_EQ(a.size(), chart.grid().count());
  EXPECT_EQ(countDifferentBits(a, b), 0u);

  p.seed = 43;
  const std::vector<float> c = generateRelief(chart, p);
  EXPECT_GT(countDifferentBits(a, c), a.size() * 9 / 10) << "another seed, another planet";
}

// OpenMP is required by the build (CMakeLists.txt), so this always runs.
TEST(Relief, DoesNotDependOnThreadCount) {
  const LatLongChart chart(GridSize(8), kRadius);
  const ReliefParams p;
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<float> one = generateRelief(chart, p);
  omp_set_num_threads(3);
  const std::vector<float> three = generateRelief(chart, p);
  omp_set_num_threads(before);
  EXPECT_EQ(countDifferentBits(one, three), 0u);
}

TEST(Relief, SeamTwinsAndPoleRowsAreBitwiseEqual) {
  const LatLongChart chart(GridSize(9), kRadius);
  ReliefParams p;
  p.seed = 7;
  const std::vector<float> h = generateRelief(chart, p);
  const GridSize& g = chart.grid();
  const int m = g.m();
  for (int v = 0; v <= m; ++v) {
    ASSERT_TRUE(sameBits(h[g.index(0, v)], h[g.index(m, v)])) << "seam twins differ at v = " << v;
  }
  for (const int v : {0, m}) {
    for (int u = 1; u <= m; ++u) {
      ASSERT_TRUE(sameBits(h[g.index(u, v)], h[g.index(0, v)]))
          << "pole row " << v << ", u = " << u;
    }
  }
}

TEST(Relief, StaysWithinAmplitudeAndUsesMostOfTheRange) {
  const LatLongChart chart(GridSize(9), kRadius);
  const struct {
    std::uint64_t seed;
    double amplitude;
  } cases[] = {{1, 8000.0}, {2, 8000.0}, {3, 1234.5}};
  for (const auto& c : cases) {
    ReliefParams p;
    p.seed = c.seed;
    p.amplitudeMetres = c.amplitude;
    const std::vector<float> h = generateRelief(chart, p);
    float lo = std::numeric_limits<float>::max(), hi = -lo;
    for (const float x : h) {
      ASSERT_TRUE(std::isfinite(x));
      ASSERT_LE(std::abs(double(x)), c.amplitude);
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    EXPECT_LT(lo, -0.6 * c.amplitude) << "seed " << c.seed << ": deep ocean basins";
    EXPECT_GT(hi, 0.7 * c.amplitude) << "seed " << c.seed << ": high peaks";
  }
}

TEST(Relief, HasOceansAndContinents) {
  const LatLongChart chart(GridSize(9), kRadius);
  const ReliefParams p;
  const std::vector<float> h = generateRelief(chart, p);
  const GridSize& g = chart.grid();
  // Area-weighted fractions (a lat-long row covers cos(latitude) of the equator's area).
  double total = 0.0, land = 0.0, abyss = 0.0;
  for (int v = 0; v <= g.m(); ++v) {
    const double w = std::cos(chart.latitude(v));
    for (int u = 0; u < g.m(); ++u) {
      const float x = h[g.index(u, v)];
      total += w;
      land += x > 0.0f ? w : 0.0;
      abyss += (x < -3000.0f && x > -6500.0f) ? w : 0.0;
    }
  }
  EXPECT_GT(land / total, 0.15);
  EXPECT_LT(land / total, 0.5);
  EXPECT_GT(abyss / total, 0.3) << "most of the ocean is deep sea floor";
}

TEST(Relief, ReliefAtMatchesGeneratedVertices) {
  const LatLongChart chart(GridSize(8), kRadius);
  ReliefParams p;
  p.seed = 99;
  const std::vector<float> h = generateRelief(chart, p);
  const int octaves = reliefOctaves(chart.grid(), p);
  const GridSize& g = chart.grid();
  const int m = g.m();
  int checked = 0;
  for (int v = 0; v <= m; v += 9) {
    for (int u = 0; u <= m; u += 11) {
      const double at = reliefAt(chart.up(u, v), p, octaves);
      ASSERT_TRUE(sameBits(static_cast<float>(at), h[g.index(u, v)])) << u << ", " << v;
      ++checked;
    }
  }
  for (const int v : {0, m}) {
    EXPECT_TRUE(
        sameBits(static_cast<float>(reliefAt(chart.up(3, v), p, octaves)), h[g.index(3, v)]));
  }
  EXPECT_TRUE(
      sameBits(static_cast<float>(reliefAt(chart.up(m, 77), p, octaves)), h[g.index(m, 77)]));
  EXPECT_GT(checked, 500);
}

TEST(Relief, GenericChartPathGivesTheSameHeights) {
  const LatLongChart chart(GridSize(7), kRadius);
  const WrappedChart wrapped(chart);
  const ReliefParams p;
  EXPECT_EQ(countDifferentBits(generateRelief(chart, p), generateRelief(wrapped, p)), 0u);
}

// Charts without a shared z per row evaluate a row's directions together, each with its own z:
// every vertex must still be reliefAt's value for its up direction, bit for bit.
TEST(Relief, RowsWithoutASharedZAreEachDirectionsRelief) {
  const ps::core::OctahedralChart octahedral(GridSize(7), kRadius);
  const ps::core::TorusChart torus(GridSize(7), kRadius, 0.3 * kRadius);
  ReliefParams p;
  p.seed = 7;
  for (const Chart* chart :
       {static_cast<const Chart*>(&octahedral), static_cast<const Chart*>(&torus)}) {
    const std::vector<float> h = generateRelief(*chart, p);
    const int octaves = reliefOctaves(chart->grid(), p);
    const GridSize& g = chart->grid();
    std::size_t checked = 0, different = 0;
    for (int v = 0; v <= g.m(); v += 3) {
      for (int u = 0; u <= g.m(); u += 5) {
        const float at = static_cast<float>(reliefAt(chart->up(u, v), p, octaves));
        different += sameBits(at, h[g.index(u, v)]) ? 0 : 1;
        ++checked;
      }
    }
    EXPECT_EQ(different, 0u) << chart->name() << ": of " << checked;
    EXPECT_GT(checked, 1000u);
  }
}

TEST(Relief, IsSmoothAcrossTheSeam) {
  const LatLongChart chart(GridSize(9), kRadius);
  ReliefParams p;
  p.seed = 5;
  const std::vector<float> h = generateRelief(chart, p);
  const GridSize& g = chart.grid();
  const int m = g.m();
  // Mean |h(u+1) - h(u-1)| down a column pair two cells apart. Across the seam that pair is
  // columns 1 and m-1.
  auto spread = [&](int left, int right) {
    double sum = 0.0;
    for (int v = 1; v < m; ++v) sum += std::abs(double(h[g.index(right, v)]) - h[g.index(left, v)]);
    return sum / (m - 1);
  };
  const double seam = spread(m - 1, 1);
  double typical = 0.0, largest = 0.0;
  for (int u = 1; u + 1 < m; ++u) {
    const double s = spread(u - 1, u + 1);
    typical += s / (m - 2);
    largest = std::max(largest, s);
  }
  EXPECT_GT(seam, 0.0);
  EXPECT_LT(seam, 2.0 * typical) << "seam " << seam << " m vs typical " << typical << " m";
  EXPECT_LE(seam, largest);
}

TEST(Relief, ChoosesOctavesFromTheGrid) {
  const ReliefParams automatic;
  int previous = 0;
  for (int n = GridSize::kMinLevel; n <= GridSize::kMaxLevel; ++n) {
    const int octaves = reliefOctaves(GridSize(n), automatic);
    EXPECT_GE(octaves, previous) << "finer grids resolve finer octaves";
    EXPECT_GE(octaves, 1);
    EXPECT_LE(octaves, 14);
    previous = octaves;
  }
  EXPECT_GT(reliefOctaves(GridSize(13), automatic), reliefOctaves(GridSize(9), automatic));
  ReliefParams fixed;
  fixed.octaves = 3;
  EXPECT_EQ(reliefOctaves(GridSize(13), fixed), 3);

  // Extra octaves add detail and leave the continents where they were.
  const LatLongChart chart(GridSize(8), kRadius);
  const std::vector<float> coarse = generateRelief(chart, fixed);
  fixed.octaves = 9;
  const std::vector<float> fine = generateRelief(chart, fixed);
  std::size_t agree = 0;
  for (std::size_t i = 0; i < coarse.size(); ++i) agree += (coarse[i] > 0) == (fine[i] > 0) ? 1 : 0;
  EXPECT_GT(agree, coarse.size() * 85 / 100);
  EXPECT_GT(countDifferentBits(coarse, fine), coarse.size() / 2);
}

TEST(Relief, ReportsProgressFromTheCallingThread) {
  const LatLongChart chart(GridSize(9), kRadius);
  std::vector<double> seen;
  bool otherThread = false;
  const std::thread::id caller = std::this_thread::get_id();
  generateRelief(chart, ReliefParams{}, [&](double f) {
    otherThread = otherThread || std::this_thread::get_id() != caller;
    seen.push_back(f);
  });
  EXPECT_FALSE(otherThread);
  ASSERT_GE(seen.size(), 3u);
  EXPECT_EQ(seen.front(), 0.0);
  EXPECT_EQ(seen.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  for (const double f : seen) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
  }

  // A progress callback that throws (a cancel button) stops the run; the exception comes out.
  auto cancel = [](double f) {
    if (f > 0.0) throw std::runtime_error("cancelled");
  };
  EXPECT_THROW(generateRelief(chart, ReliefParams{}, cancel), std::runtime_error);
}

TEST(Relief, RejectsBadParams) {
  const LatLongChart chart(GridSize(5), kRadius);
  auto expectInputError = [&](const ReliefParams& p, const std::string& named) {
    try {
      generateRelief(chart, p);
      ADD_FAILURE() << "accepted " << named;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  };
  ReliefParams p;
  p.amplitudeMetres = 0.0;
  expectInputError(p, "0");
  p.amplitudeMetres = -5.0;
  expectInputError(p, "-5");
  p.amplitudeMetres = std::numeric_limits<double>::quiet_NaN();
  expectInputError(p, "nan");
  p.amplitudeMetres = std::numeric_limits<double>::infinity();
  expectInputError(p, "inf");
  p = ReliefParams{};
  p.octaves = -1;
  expectInputError(p, "-1");
  p.octaves = 21;
  expectInputError(p, "21");
  p.octaves = 20;
  EXPECT_NO_THROW(generateRelief(chart, p));

  const Eigen::Vector3d north(0.0, 0.0, 1.0);
  EXPECT_THROW(reliefAt(north, ReliefParams{}, 0), InputError);
  EXPECT_THROW(reliefAt(north, ReliefParams{}, 21), InputError);
  ReliefParams badAmplitude;
  badAmplitude.amplitudeMetres = -1.0;
  EXPECT_THROW(reliefAt(north, badAmplitude, 5), InputError);
  EXPECT_THROW(reliefOctaves(GridSize(9), badAmplitude), InputError);
}
