#include "terrain/gradient_noise.hpp"

#include <array>
#include <cstring>
#include <limits>

namespace ps::terrain::noise {

namespace {

// ---- Seeding -----------------------------------------------------------------------------------

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// 53 random bits as a double in [0, 1): exact, so identical everywhere.
double unitInterval(std::uint64_t bits) {
  return double(bits >> 11) * 0x1.0p-53;
}

// ---- Gradient noise ----------------------------------------------------------------------------
// Improved Perlin noise, four points at a time with GCC vector extensions (SSE2 pairs in a
// baseline x86-64 build, single AVX2 registers in the avx2 clone of noiseBatch). Every point,
// reliefAt's lone one included, goes through the same lane code using only + - * and exact
// conversions (the avx2 target does not enable FMA), so all paths agree to the bit.
//
// Vectors are passed by reference: 32-byte vectors by value draw GCC's -Wpsabi warning about the
// AVX calling convention.

using VecD = double __attribute__((vector_size(32)));
using VecL = std::int64_t __attribute__((vector_size(32)));
using VecI = std::int32_t __attribute__((vector_size(16)));
using VecU = std::uint32_t __attribute__((vector_size(16)));

// Multipliers that spread lattice coordinates over 32 bits before the avalanche below.
constexpr std::uint32_t kPx = 0x8DA6B343u;
constexpr std::uint32_t kPy = 0xD8163841u;
constexpr std::uint32_t kPz = 0xCB1AB31Fu;

// Truncation plus a fix-up is exact and much cheaper than std::floor; coordinates are far inside
// int range (|p| <= 1, frequencies below 2^21, offsets below 256).
int fastFloor(double x) {
  const int i = static_cast<int>(x);
  return i - (x < static_cast<double>(i) ? 1 : 0);
}

[[gnu::always_inline]] inline VecI floor4(const VecD& x) {
  const VecI i = __builtin_convertvector(x, VecI);
  const VecL below = x < __builtin_convertvector(i, VecD);  // -1 where truncation rounded up
  return i + __builtin_convertvector(below, VecI);
}

double fade(double t) {
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// Avalanches lattice code h like lowbias32's first half and keeps the top four bits, which the
// multiplies mix best: the index of one of Ken Perlin's improved gradients (the 12 cube edge
// midpoints, four of them twice). Widened to 64-bit lanes to line up with the doubles.
[[gnu::always_inline]] inline void gradientCode(VecU h, VecL& code) {
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  // Zero-extension written as an interleave with zeros: a single vpmovzxdq, where
  // __builtin_convertvector makes GCC 12 split the vector in halves.
  const VecU zero{};
  code = reinterpret_cast<VecL>(__builtin_shufflevector(h >> 28, zero, 0, 4, 1, 4, 2, 4, 3, 4));
}

// Perlin's selection (u, v and two signs) instead of a table lookup, so the lanes need no gather.
[[gnu::always_inline]] inline void gradDot(const VecL& g, const VecD& fx, const VecD& fy,
                                           const VecD& fz, VecD& out) {
  const VecD u = g < 8 ? fx : fy;
  const VecD v = g < 4 ? fy : ((g == 12) | (g == 14)) ? fx : fz;
  const VecL uSign = (g & 1) << 63, vSign = (g & 2) << 62;
  out = reinterpret_cast<VecD>(reinterpret_cast<VecL>(u) ^ uSign) +
        reinterpret_cast<VecD>(reinterpret_cast<VecL>(v) ^ vSign);
}

// The same gradients as vectors, for the cached path of noiseBatch.
struct Gradient {
  double x, y, z;
};
constexpr std::array<Gradient, 16> makeGradients() {
  std::array<Gradient, 16> table{};
  for (int g = 0; g < 16; ++g) {
    double c[3] = {0.0, 0.0, 0.0};
    c[g < 8 ? 0 : 1] = (g & 1) ? -1.0 : 1.0;
    c[g < 4 ? 1 : (g == 12 || g == 14) ? 0 : 2] = (g & 2) ? -1.0 : 1.0;
    table[std::size_t(g)] = {c[0], c[1], c[2]};
  }
  return table;
}
constexpr std::array<Gradient, 16> kGradients = makeGradients();

// The lane helpers both noiseBatch forms share, so that they give a point the same bits.
// Perlin's fade 6t^5 - 15t^4 + 10t^3, the scalar fade()'s arithmetic in each lane.
[[gnu::always_inline]] inline void fade4(const VecD& t, VecD& out) {
  out = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}
// The hash inputs of the four (x, y) corners of each lane's lattice cell: (ix, iy), (ix + 1, iy),
// (ix, iy + 1), (ix + 1, iy + 1).
[[gnu::always_inline]] inline void cornerCodesXY(const VecI& ix, const VecI& iy, VecU b[4]) {
  const VecU b00 =
      reinterpret_cast<const VecU&>(ix) * kPx + reinterpret_cast<const VecU&>(iy) * kPy;
  b[0] = b00;
  b[1] = b00 + kPx;
  b[2] = b00 + kPy;
  b[3] = b00 + (kPx + kPy);
}
// Trilinear blend of the eight corners' values with the faded weights (x, then y, then z), times
// `scale`, stored into out[0 .. kLanes) or added to it.
[[gnu::always_inline]] inline void blendInto(const VecD n[8], const VecD& wx, const VecD& wy,
                                             const VecD& wz, double scale, bool accumulate,
                                             double* out) {
  const VecD n00 = n[0] + wx * (n[1] - n[0]), n10 = n[2] + wx * (n[3] - n[2]);
  const VecD n01 = n[4] + wx * (n[5] - n[4]), n11 = n[6] + wx * (n[7] - n[6]);
  const VecD n0 = n00 + wy * (n10 - n00), n1 = n01 + wy * (n11 - n01);
  VecD result = scale * (n0 + wz * (n1 - n0));
  if (accumulate) {
    VecD previous;
    std::memcpy(&previous, out, sizeof previous);
    result = previous + result;
  }
  std::memcpy(out, &result, sizeof result);
}

}  // namespace

Octave makeOctave(std::uint64_t seed, std::uint64_t layer, int k, double freq) {
  // Derived from (seed, layer, k) alone so that adding octaves (a finer grid) keeps the coarse
  // shape of the planet unchanged.
  const std::uint64_t base = splitmix64(seed ^ splitmix64(layer * 64 + std::uint64_t(k) + 1));
  Octave o;
  o.freq = freq;
  o.ox = 256.0 * unitInterval(splitmix64(base + 1));
  o.oy = 256.0 * unitInterval(splitmix64(base + 2));
  o.oz = 256.0 * unitInterval(splitmix64(base + 3));
  o.seed = static_cast<std::uint32_t>(splitmix64(base + 4) >> 32);
  return o;
}

// Noise of octave `o` (range about [-1, 1]) at the points (x[i], y[i], z), i < count, times
// `scale`, stored into out[i] or, with `accumulate`, added to it. The arrays must be readable and
// writable up to count rounded up to kLanes.
//
// Two savings, neither of which changes a bit of the result:
//  - A lat-long row has one z, so the z half of the lattice lookup is done once per call.
//  - Below the finest octaves, runs of neighbouring vertices share a lattice cell. When all four
//    lanes sit in the cell of the previous block, the eight gradients are reused and each corner
//    costs two multiplies and two adds instead of a hash. The cached form g.x*fx + g.y*fy + g.z*fz
//    adds a zero term to the selected u + v, which leaves every non-zero dot product unchanged;
//    at worst a zero's sign differs, and such a zero disappears in the next sum.
__attribute__((target_clones("avx2", "default"))) void noiseBatch(const Octave& o, double z,
                                                                  const double* x, const double* y,
                                                                  int count, double* out,
                                                                  double scale, bool accumulate) {
  const double zz = z * o.freq + o.oz;
  const int iz = fastFloor(zz);
  const double fzs[2] = {zz - iz, zz - iz - 1.0};
  const VecD fz[2] = {VecD{} + fzs[0], VecD{} + fzs[1]};
  const VecD wz = VecD{} + fade(fzs[0]);
  const std::uint32_t hz = o.seed + static_cast<std::uint32_t>(iz) * kPz;
  const VecU h[2] = {VecU{} + hz, VecU{} + (hz + kPz)};

  int cellX = std::numeric_limits<int>::min(), cellY = cellX;  // no cell cached yet
  double cgx[8] = {}, cgy[8] = {}, cgz[8] = {};                // cgz: g.z * fz, per row

  for (int i = 0; i < count; i += kLanes) {
    VecD px, py;
    std::memcpy(&px, x + i, sizeof px);
    std::memcpy(&py, y + i, sizeof py);
    const VecD xx = px * o.freq + o.ox;
    const VecD yy = py * o.freq + o.oy;
    const VecI ix = floor4(xx), iy = floor4(yy);
    const VecD fx[2] = {xx - __builtin_convertvector(ix, VecD), fx[0] - 1.0};
    const VecD fy[2] = {yy - __builtin_convertvector(iy, VecD), fy[0] - 1.0};
    VecD wx, wy;
    fade4(fx[0], wx);
    fade4(fy[0], wy);

    // Corner c is (ix + (c & 1), iy + (c >> 1 & 1), iz + (c >> 2)).
    VecD n[8];
    std::uint64_t other[2];
    const VecI moved = (ix ^ cellX) | (iy ^ cellY);
    std::memcpy(other, &moved, sizeof other);
    if ((other[0] | other[1]) == 0) {
#pragma GCC unroll 8
      for (int c = 0; c < 8; ++c) n[c] = cgx[c] * fx[c & 1] + cgy[c] * fy[c >> 1 & 1] + cgz[c];
    } else {
      VecU b[4];
      cornerCodesXY(ix, iy, b);
      VecL g[8];
#pragma GCC unroll 8
      for (int c = 0; c < 8; ++c) {
        gradientCode(h[c >> 2] + b[c & 3], g[c]);
        gradDot(g[c], fx[c & 1], fy[c >> 1 & 1], fz[c >> 2], n[c]);
      }
      // Cache the last lane's cell: the next block most likely starts in it.
      cellX = ix[kLanes - 1];
      cellY = iy[kLanes - 1];
      for (int c = 0; c < 8; ++c) {
        const Gradient& grad = kGradients[std::size_t(g[c][kLanes - 1])];
        cgx[c] = grad.x;
        cgy[c] = grad.y;
        cgz[c] = grad.z * fzs[c >> 2];
      }
    }
    blendInto(n, wx, wy, wz, scale, accumulate, out + i);
  }
}

// noiseBatch for points that each have their own z (charts whose rows do not share one: the
// octahedral chart, the torus): the same lane arithmetic as noiseBatch's uncached path, so a
// point gets the same bits either way (the generic-chart test compares them with lat-long's).
__attribute__((target_clones("avx2", "default"))) void noiseBatchXYZ(
    const Octave& o, const double* x, const double* y, const double* z, int count, double* out,
    double scale, bool accumulate) {
  for (int i = 0; i < count; i += kLanes) {
    VecD px, py, pz;
    std::memcpy(&px, x + i, sizeof px);
    std::memcpy(&py, y + i, sizeof py);
    std::memcpy(&pz, z + i, sizeof pz);
    const VecD xx = px * o.freq + o.ox;
    const VecD yy = py * o.freq + o.oy;
    const VecD zz = pz * o.freq + o.oz;
    const VecI ix = floor4(xx), iy = floor4(yy), iz = floor4(zz);
    const VecD fx[2] = {xx - __builtin_convertvector(ix, VecD), fx[0] - 1.0};
    const VecD fy[2] = {yy - __builtin_convertvector(iy, VecD), fy[0] - 1.0};
    const VecD fz[2] = {zz - __builtin_convertvector(iz, VecD), fz[0] - 1.0};
    VecD wx, wy;
    fade4(fx[0], wx);
    fade4(fy[0], wy);
    VecD wz;
    fade4(fz[0], wz);
    const VecU hz = o.seed + reinterpret_cast<const VecU&>(iz) * kPz;
    const VecU h[2] = {hz, hz + kPz};
    VecU b[4];
    cornerCodesXY(ix, iy, b);
    VecD n[8];
#pragma GCC unroll 8
    for (int c = 0; c < 8; ++c) {
      VecL g;
      gradientCode(h[c >> 2] + b[c & 3], g);
      gradDot(g, fx[c & 1], fy[c >> 1 & 1], fz[c >> 2], n[c]);
    }
    blendInto(n, wx, wy, wz, scale, accumulate, out + i);
  }
}

}  // namespace ps::terrain::noise
