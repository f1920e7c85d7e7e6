#include "terrain/relief.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "terrain/gradient_noise.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace ps::terrain {

namespace {

using noise::kLanes;
using noise::makeOctave;
using noise::noiseBatch;
using noise::noiseBatchXYZ;
using noise::Octave;

// ---- Shaping -----------------------------------------------------------------------------------
// Elevations here are in units of the amplitude (1 = 8 km by default). The per-vertex stages are
// free of branches (clamps are written with fabs, which GCC's vectoriser takes where it refuses
// std::min/max on doubles) so that `omp simd` vectorises them; elementwise IEEE arithmetic gives
// the same bits in vector and scalar code.

// max(y, 0) and clamp(y, 0, 1). Exact for y >= 0 and y in [0, 1] respectively, up to rounding in
// the last bit of the latter, which is harmless in a ramp.
[[gnu::always_inline]] inline double positive(double y) {
  return 0.5 * (y + std::abs(y));
}
[[gnu::always_inline]] inline double clamp01(double y) {
  return 0.5 * ((std::abs(y) - std::abs(y - 1.0)) + 1.0);
}

// Smoothstep from 0 at x = e0 to 1 at x = e0 + 1/invWidth (invWidth < 0 runs downhill).
[[gnu::always_inline]] inline double ramp(double x, double e0, double invWidth) {
  const double t = clamp01((x - e0) * invWidth);
  return t * (t * (3.0 - 2.0 * t));
}

// Hypsometric curve from the continent signal t (0 at the coast) to base elevation: a sum of
// smoothsteps, so it is monotone with flat stretches where Earth's hypsometry has its two humps,
// the abyssal plains and the continental lowlands, and steep ones at the continental slope.
[[gnu::always_inline]] inline double hypsometry(double t) {
  return -0.78                              // deep basins, ~-6.2 km
         + 0.16 * ramp(t, -0.60, 1 / 0.40)  // up to the abyssal plains, ~-5 km
         + 0.54 * ramp(t, -0.15, 1 / 0.10)  // continental slope up to the shelf break, ~-500 m
         + 0.08 * ramp(t, -0.07, 1 / 0.08)  // shelf, reaching the coast near t = 0
         + 0.24 * ramp(t, 0.00, 1 / 0.70);  // lowlands to high plateaus, ~1.9 km
}

// Smooth clamp into (-1, 1), tanh-like: the identity up to |e| = 1/2 (sea floor and land keep
// their shape), then a C1 rational saturation 1 - 1/(1 + r + r^2/2 + r^3/6), which closes in on 1
// as fast as 1/r^3. Division only: libm's tanh is not bitwise the same everywhere, and
// std::sqrt blocks vectorisation (errno).
[[gnu::always_inline]] inline double softClamp(double e) {
  constexpr double kKnee = 0.5;
  const double a = std::abs(e);
  const double excess = positive(a - kKnee);
  const double r = excess * (1.0 / (1.0 - kKnee));
  const double saturated = 1.0 - 1.0 / (1.0 + r * (1.0 + r * (0.5 + r * (1.0 / 6.0))));
  return std::copysign((a - excess) + (1.0 - kKnee) * saturated, e);
}

constexpr double kSeaLevel = 0.12;  // continent signal at the coast: about 30% land

// Base elevation and mountain mask from the fBm split (cont: coarse octaves, detail: the rest)
// and the belt noise.
__attribute__((target_clones("avx2", "default"))) void shapeStage(int count, const double* cont,
                                                                  const double* detail,
                                                                  const double* beltNoise,
                                                                  double* base, double* mask) {
#pragma omp simd
  for (int i = 0; i < count; ++i) {
    const double t = cont[i] + detail[i] - kSeaLevel;
    const double land = ramp(t, 0.0, 1 / 0.12);
    const double deep = ramp(t, -0.12, -1 / 0.18);
    // The detail octaves bend the belts so ranges wander instead of following smooth arcs.
    const double belt = std::abs(beltNoise[i] + 0.5 * detail[i]);
    double e = hypsometry(t);
    e += (0.02 + 0.2 * land) * detail[i];  // gentle sea floor, hills on land
    // Broad uplift around the ranges (plateaus, foothills), and mid-ocean ridges along the same
    // lines on the deep sea floor.
    e += 0.08 * land * ramp(belt, 0.2, -1 / 0.2);
    e += 0.2 * deep * ramp(belt, 0.12, -1 / 0.12);
    base[i] = e;
    mask[i] = land * ramp(belt, 0.07, -1 / 0.07);
  }
}

// Adds the mountains (ridged signal where mask > 0) and clamps into [-amplitude, amplitude].
__attribute__((target_clones("avx2", "default"))) void finishStage(int count, const double* base,
                                                                   const double* mask,
                                                                   const double* ridge,
                                                                   double amplitude, double* out) {
#pragma omp simd
  for (int i = 0; i < count; ++i) {
    // The ridged sum mostly lies in [0.6, 1.8]: crests near the top carry the peaks.
    const double q = positive(ridge[i] - 0.6) * (1.0 / 1.2);
    out[i] = amplitude * softClamp(base[i] + mask[i] * (q * q));
  }
}

// ---- The field ---------------------------------------------------------------------------------

constexpr double kContinentFreq = 1.1;  // a handful of continents
constexpr double kBeltFreq = 1.3;       // layout of mountain belts and mid-ocean ridges
constexpr double kRidgeFreq = 2.2;      // first ridged octave: individual ranges
constexpr double kLacunarity = 2.0;
constexpr int kMaxDefaultOctaves = 14;
constexpr int kMaxOctaves = 20;
constexpr int kCoarseOctaves = 2;  // continent octaves that are not also "detail"

constexpr std::size_t padded(int count) {
  return static_cast<std::size_t>((count + kLanes - 1) / kLanes * kLanes);
}

// Per-thread buffers for one row.
struct Scratch {
  std::vector<double> noise, cont, detail, belt, base, mask, ridge, cx, cy, cz, cr, cw;
  std::vector<int> active;
  explicit Scratch(int count) {
    const std::size_t n = padded(count);
    for (auto* v : {&noise, &cont, &detail, &belt, &base, &mask, &ridge, &cx, &cy, &cz, &cr, &cw}) {
      v->resize(n);
    }
    active.resize(n);
  }
};

class ReliefField {
 public:
  ReliefField(const ReliefParams& params, int octaves) : amplitude_(params.amplitudeMetres) {
    double f = kContinentFreq;
    for (int k = 0; k < octaves; ++k, f *= kLacunarity) {
      fbm_.push_back(makeOctave(params.seed, 1, k, f));
    }
    // Same finest frequency as the fBm: the ridges start one octave higher.
    f = kRidgeFreq;
    for (int k = 0; k + 1 < octaves; ++k, f *= kLacunarity) {
      ridged_.push_back(makeOctave(params.seed, 2, k, f));
    }
    belt_ = makeOctave(params.seed, 3, 0, kBeltFreq);
  }

  // Heights in metres for the `count` directions (x[i], y[i], z), or (x[i], y[i], zs[i]) where
  // zs is not null; x, y (and zs) padded as noiseBatch requires.
  void evalRow(const double* x, const double* y, double z, int count, double* out, Scratch& s,
               const double* zs = nullptr) const {
    auto noise = [&](const Octave& o, const double* px, const double* py, const double* pz, int n,
                     double* dst, double scale, bool accumulate) {
      if (zs) {
        noiseBatchXYZ(o, px, py, pz, n, dst, scale, accumulate);
      } else {
        noiseBatch(o, z, px, py, n, dst, scale, accumulate);
      }
    };
    double amp = 1.0;
    for (std::size_t k = 0; k < fbm_.size(); ++k, amp *= 0.5) {
      const bool coarse = static_cast<int>(k) < kCoarseOctaves;
      const bool first = k == 0 || static_cast<int>(k) == kCoarseOctaves;
      noise(fbm_[k], x, y, zs, count, (coarse ? s.cont : s.detail).data(), amp, !first);
    }
    if (static_cast<int>(fbm_.size()) <= kCoarseOctaves) {
      std::fill(s.detail.begin(), s.detail.end(), 0.0);
    }
    noise(belt_, x, y, zs, count, s.belt.data(), 1.0, false);
    shapeStage(count, s.cont.data(), s.detail.data(), s.belt.data(), s.base.data(), s.mask.data());

    std::fill(s.ridge.begin(), s.ridge.end(), 0.0);
    std::size_t nActive = 0;
    for (int i = 0; i < count; ++i) {
      if (s.mask[std::size_t(i)] > 0.0) {
        s.active[nActive] = i;
        s.cx[nActive] = x[i];
        s.cy[nActive] = y[i];
        if (zs) s.cz[nActive] = zs[i];
        s.cr[nActive] = 0.0;
        s.cw[nActive] = 1.0;
        ++nActive;
      }
    }

    // Ridged multifractal (Musgrave) on the mountain belts only, over a packed list of their
    // vertices: each octave is weighted by the previous one's signal, so detail piles up on crests
    // and valleys stay smooth. A vertex whose weight has all but vanished (finer octaves could
    // add about a metre) leaves the list.
    double octaveAmp = 1.0;
    for (std::size_t k = 0; k < ridged_.size() && nActive > 0; ++k, octaveAmp *= 0.5) {
      for (std::size_t j = nActive; j < padded(int(nActive)); ++j) {
        s.cx[j] = s.cx[j - 1];
        s.cy[j] = s.cy[j - 1];
        s.cz[j] = s.cz[j - 1];
      }
      noise(ridged_[k], s.cx.data(), s.cy.data(), s.cz.data(), int(nActive), s.noise.data(), 1.0,
            false);
      std::size_t nNext = 0;
      for (std::size_t j = 0; j < nActive; ++j) {
        double signal = 1.0 - std::abs(s.noise[j]);
        signal *= signal;
        signal *= s.cw[j];
        const double r = s.cr[j] + signal * octaveAmp;
        const double w = std::min(1.0, signal * 2.0);
        if (w > kRidgeCutoff) {
          s.active[nNext] = s.active[j];
          s.cx[nNext] = s.cx[j];
          s.cy[nNext] = s.cy[j];
          s.cz[nNext] = s.cz[j];
          s.cr[nNext] = r;
          s.cw[nNext] = w;
          ++nNext;
        } else {
          s.ridge[std::size_t(s.active[j])] = r;
        }
      }
      nActive = nNext;
    }
    for (std::size_t j = 0; j < nActive; ++j) s.ridge[std::size_t(s.active[j])] = s.cr[j];

    finishStage(count, s.base.data(), s.mask.data(), s.ridge.data(), amplitude_, out);
  }

 private:
  static constexpr double kRidgeCutoff = 1.0 / 8192.0;

  double amplitude_;
  std::vector<Octave> fbm_, ridged_;
  Octave belt_;
};

void validate(const ReliefParams& params) {
  if (!std::isfinite(params.amplitudeMetres) || params.amplitudeMetres <= 0.0) {
    std::ostringstream msg;
    msg << "relief amplitude " << params.amplitudeMetres << " m must be positive and finite";
    throw core::InputError(msg.str());
  }
  if (params.octaves < 0 || params.octaves > kMaxOctaves) {
    throw core::InputError("relief octaves = " + std::to_string(params.octaves) +
                           " is out of range: 0 (automatic) to " + std::to_string(kMaxOctaves));
  }
}

}  // namespace

int reliefOctaves(const core::GridSize& grid, const ReliefParams& params) {
  validate(params);
  if (params.octaves > 0) return params.octaves;
  // Noise at lattice frequency f repeats about every 1/f radians. Keep octaves while that still
  // spans two cells where the grid is coarsest, along the equator (2*pi/m per cell).
  const double fMax = grid.m() / (4.0 * std::numbers::pi);
  int n = 1;
  for (double f = kContinentFreq * kLacunarity; f <= fMax && n < kMaxDefaultOctaves;
       f *= kLacunarity) {
    ++n;
  }
  return n;
}

double reliefAt(const Eigen::Vector3d& unitDirection, const ReliefParams& params, int octaves) {
  validate(params);
  if (octaves < 1 || octaves > kMaxOctaves) {
    throw core::InputError("relief octaves = " + std::to_string(octaves) +
                           " is out of range: 1 to " + std::to_string(kMaxOctaves));
  }
  const ReliefField field(params, octaves);
  Scratch s(1);
  double x[kLanes], y[kLanes], h[kLanes];
  std::fill_n(x, kLanes, unitDirection.x());
  std::fill_n(y, kLanes, unitDirection.y());
  field.evalRow(x, y, unitDirection.z(), 1, h, s);
  return h[0];
}

std::vector<float> generateRelief(const core::Chart& chart, const ReliefParams& params,
                                  const std::function<void(double)>& progress) {
  const core::GridSize grid = chart.grid();
  const int octaves = reliefOctaves(grid, params);
  const ReliefField field(params, octaves);
  const int side = grid.side();
  std::vector<float> heights(grid.count());
  const auto* latLong = dynamic_cast<const core::LatLongChart*>(&chart);

  if (progress) progress(0.0);
  std::atomic<int> rowsDone{0};
  std::atomic<bool> stop{false};
  std::exception_ptr error;
  // Only the calling thread reports, after its own rows, about every 1% of the grid.
  const int reportEvery = std::max(1, side / 100);
  int lastReported = 0;

#pragma omp parallel
  {
    Scratch s(side);
    const std::size_t n = padded(side);
    std::vector<double> x(n), y(n), z(n), out(n);
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < side; ++v) {
      if (stop.load(std::memory_order_relaxed)) continue;
      float* row = heights.data() + grid.index(0, v);
      if (latLong) {
        for (int u = 0; u < side; ++u) {
          const Eigen::Vector3d d = latLong->direction(u, v);
          x[std::size_t(u)] = d.x();
          y[std::size_t(u)] = d.y();
        }
        std::fill(x.begin() + side, x.end(), x[std::size_t(side) - 1]);
        std::fill(y.begin() + side, y.end(), y[std::size_t(side) - 1]);
        field.evalRow(x.data(), y.data(), latLong->direction(0, v).z(), side, out.data(), s);
        for (int u = 0; u < side; ++u) row[u] = static_cast<float>(out[std::size_t(u)]);
      } else {
        // Any other chart: no shared z per row, so each direction brings its own.
        for (int u = 0; u < side; ++u) {
          const Eigen::Vector3d d = chart.up(u, v);
          x[std::size_t(u)] = d.x();
          y[std::size_t(u)] = d.y();
          z[std::size_t(u)] = d.z();
        }
        for (std::size_t k = std::size_t(side); k < n; ++k) {
          x[k] = x[k - 1];
          y[k] = y[k - 1];
          z[k] = z[k - 1];
        }
        field.evalRow(x.data(), y.data(), 0.0, side, out.data(), s, z.data());
        for (int u = 0; u < side; ++u) row[u] = static_cast<float>(out[std::size_t(u)]);
      }
      const int done = rowsDone.fetch_add(1, std::memory_order_relaxed) + 1;
#ifdef _OPENMP
      const bool caller = omp_get_thread_num() == 0;  // the master thread is the calling thread
#else
      const bool caller = true;
#endif
      if (caller && progress && done - lastReported >= reportEvery) {
        lastReported = done;
        try {
          progress(double(done) / side);
        } catch (...) {
          // An exception must not leave the parallel region: stop the others, rethrow after it.
          error = std::current_exception();
          stop.store(true, std::memory_order_relaxed);
        }
      }
    }
  }
  if (error) std::rethrow_exception(error);
  if (progress) progress(1.0);
  return heights;
}

}  // namespace ps::terrain
