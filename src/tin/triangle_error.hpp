#pragma once
// How far a TIN triangle is from the samples it covers: every lattice sample inside the
// triangle (edges included) is measured, none skipped (paper 001 samples 1-40 per triangle; the
// export guarantees its error on all of them).
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>

#include "tin/sample_field.hpp"

namespace ps::tin {

// One triangle of a TIN: lattice coordinates and heights of its three vertices.
struct LatticeTriangle {
  std::array<Eigen::Vector2d, 3> xy;
  std::array<double, 3> h;
};

struct WorstSample {
  double ratio = 0;          // error / the sample's allowed error; <= 1 means within
  double error = 0;          // metres
  std::int64_t sample = -1;  // lattice index of the sample with the largest ratio; -1: none inside
  std::int64_t samples = 0;  // how many samples the triangle covers
};

// A triangle is within its tolerance when its worst ratio is at most this: a sample exactly at
// its tolerance is not inserted (Delatin's rule too, which matters on quantised heights, where
// errors of exactly the request are common). An independent measurement, with its own rounding,
// can read such a sample at 1 + 1e-15; checks allow kCheckSlack for that.
inline constexpr double kWithinTolerance = 1.0;
inline constexpr double kCheckSlack = 1e-9;

// The sample of `field` inside `t` whose error relative to its tolerance is largest.
WorstSample worstSample(const SampleField& field, const LatticeTriangle& t);

// Distance from p to the segment ab (2D or 3D Eigen vectors; a point when a == b).
template <class V>
double pointSegmentDistance(const V& p, const V& a, const V& b) {
  const V ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + s * ab)).norm();
}

// Closed-form distance from p to the triangle abc (degenerate triangles: to their edges).
double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// Calls f(j, iFirst, iLast) for each lattice row j that the closed triangle crosses, with the
// samples iFirst..iLast of that row inside it (a hair of slack, so that samples on an edge are
// never missed to rounding; rows outside the lattice are clipped).
template <class F>
void forEachRowSpan(const LatticeTriangle& t, int width, int height, F&& f);

}  // namespace ps::tin

#include "tin/triangle_error_impl.hpp"
