#pragma once
// Improved Perlin gradient noise, four points at a time (the relief generator's engine,
// relief.cpp). Every path gives a point the same bits: the lone point of reliefAt, a lat-long
// row sharing one z, and the charts whose points each have their own z.
#include <cstdint>

namespace ps::terrain::noise {

// Points per batch step: arrays passed to noiseBatch are read and written up to their count
// rounded up to this.
inline constexpr int kLanes = 4;

// One noise layer: lattice frequency, a seeded offset (so octaves do not share lattice points at
// the origin) and a seeded hash.
struct Octave {
  double freq = 1.0;
  double ox = 0.0, oy = 0.0, oz = 0.0;
  std::uint32_t seed = 0;
};

// Octave k of noise layer `layer`, derived from (seed, layer, k) alone so that adding octaves
// (a finer grid) keeps the coarse shape of the planet unchanged.
Octave makeOctave(std::uint64_t seed, std::uint64_t layer, int k, double freq);

// Noise of octave `o` (range about [-1, 1]) at the points (x[i], y[i], z), i < count, times
// `scale`, stored into out[i] or, with `accumulate`, added to it.
void noiseBatch(const Octave& o, double z, const double* x, const double* y, int count, double* out,
                double scale, bool accumulate);
// The same for points that each have their own z (the octahedral chart, the torus).
void noiseBatchXYZ(const Octave& o, const double* x, const double* y, const double* z, int count,
                   double* out, double scale, bool accumulate);

}  // namespace ps::terrain::noise
