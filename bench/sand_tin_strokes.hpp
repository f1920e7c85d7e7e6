#pragma once
// `bench sand-tin`'s scene, paper 000's flat sand (a 10 m x 10 m box of sand 1 m deep, a disc tool
// pulled along its diagonal), and one stroke through it on each surface the bench compares: the
// sand TIN (sand::TinSand), the grid core (the same press and rampart on float heights, then
// sand::SandField's thermal erosion) and the exact shape a press-only stroke leaves. The
// experiments, their rows and plots are bench/bench_sand_tin.cpp.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/flat_chart.hpp"
#include "sand/tin_sand.hpp"
#include "tin/dynamic_tin.hpp"
#include "tin/triangle_error.hpp"

namespace ps::bench::sandtin {

struct Scene {
  double side = 10.0, sand = 1.0, radius = 0.25, depth = 0.15, spacing = 0.25;
  int erosionSteps = 2;
  double bottom() const { return sand - depth; }
  // Stamp centres along the diagonal: `trace` of its length, centred.
  std::vector<Eigen::Vector2d> stroke(double trace) const {
    const Eigen::Vector2d mid(0.5 * side, 0.5 * side), dir = Eigen::Vector2d(1, 1).normalized();
    const double half = 0.5 * trace * side * std::sqrt(2.0);
    std::vector<Eigen::Vector2d> out;
    for (double s = -half; s <= half + 1e-12; s += spacing * radius) out.push_back(mid + s * dir);
    return out;
  }
};

// A regular n x n grid of points on the sand's surface, triangulated: where the TIN starts.
tin::DynamicTin flatTin(const Scene& scene, int n);

// The steepest edge of a TIN (rise over run): how sharp an imprint it holds.
double maxEdgeSlope(const tin::DynamicTin& t);

struct TinRun {
  std::unique_ptr<sand::TinSand> sand;
  double ms = 0, drift = 0;
  std::size_t stamps = 0, erosionSteps = 0, removed = 0;
};

// The stroke (`trace` of the diagonal) on a TIN started from n x n points: a stamp every quarter
// radius, then (with `erosion`) two erosion iterations and the removal of redundant vertices.
TinRun runTin(const Scene& scene, int n, double trace, bool erosion, bool pushAside = true);

// The height at (x, y) metres, bilinear between the vertices of a side x side grid of heights
// `spacing` apart (row-major, v rows of u); clamped to the grid at its edges.
inline double bilinearAt(const std::vector<float>& heights, int side, double spacing, double x,
                         double y) {
  const double u = std::clamp(x / spacing, 0.0, double(side - 1)),
               v = std::clamp(y / spacing, 0.0, double(side - 1));
  const int i = std::min(int(u), side - 2), j = std::min(int(v), side - 2);
  const double fu = u - i, fv = v - j;
  const auto h = [&](int a, int b) { return double(heights[std::size_t(b) * side + a]); };
  return (1 - fv) * ((1 - fu) * h(i, j) + fu * h(i + 1, j)) +
         fv * ((1 - fu) * h(i, j + 1) + fu * h(i + 1, j + 1));
}

// The grid core on the same stroke: the same press (every vertex inside the tool's outline to
// its bottom) and the same rampart (what was pressed out, spread with the same profile beyond
// the outer contour), on the float heights, then SandField's thermal erosion.
struct GridRun {
  int side = 0;
  std::shared_ptr<core::FlatChart> chart;
  std::vector<float> heights;
  double ms = 0, stampMs = 0, erodeMs = 0, drift = 0;
  std::size_t stamps = 0, erosionSteps = 0, memory = 0;
  double at(double x, double y) const { return bilinearAt(heights, side, chart->dx(), x, y); }
};

// The same stroke on a grid of 2^n + 1 squared vertices.
GridRun runGrid(const Scene& scene, int n, double trace, bool erosion);

// The steepest link of a grid (rise over run).
double gridSteepest(const GridRun& g);

// RMS and largest difference of a surface from the reference grid's, over its vertices.
template <class F>
std::pair<double, double> surfaceError(const GridRun& reference, F&& heightAt) {
  const double d = reference.chart->dx();
  double sum2 = 0, worst = 0;
  for (int j = 0; j < reference.side; ++j)
    for (int i = 0; i < reference.side; ++i) {
      const double e =
          heightAt(i * d, j * d) - double(reference.heights[std::size_t(j) * reference.side + i]);
      sum2 += e * e;
      worst = std::max(worst, std::abs(e));
    }
  return {std::sqrt(sum2 / (double(reference.side) * reference.side)), worst};
}

// The exact surface a press-only stroke leaves on the flat sand: the minimum over its stamps of
// the tool's shape (the regular polygon at the bottom, its wall rising linearly across the rim to
// the sand's surface, as the TIN's contours make it), capped by the sand's surface.
struct ExactStroke {
  double sand = 0, bottom = 0, apothem = 0, rimFraction = 0, outerRadius = 0, step = 0;
  std::vector<Eigen::Vector2d> centres, normals;
  Eigen::Vector2d dir;

  ExactStroke(const Scene& scene, const sand::TinStampTool& tool, double trace)
      : sand(scene.sand), bottom(scene.bottom()), centres(scene.stroke(trace)) {
    const std::size_t n = tool.outline.size();
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector2d e = tool.outline[(k + 1) % n] - tool.outline[k];
      normals.emplace_back(e.y() / e.norm(), -e.x() / e.norm());
    }
    apothem = tool.outline[0].dot(normals[0]);
    rimFraction = tool.rim / tool.outline[0].norm();
    outerRadius = tool.outerRadius();
    step = scene.spacing * scene.radius;
    dir = Eigen::Vector2d(1, 1).normalized();
  }
  // One stamp's shape at x (the polygon's gauge: a regular polygon's outer contour is the
  // outline scaled by 1 + rim / radius).
  double tool(const Eigen::Vector2d& c, const Eigen::Vector2d& x) const {
    const Eigen::Vector2d d = x - c;
    if (d.squaredNorm() > outerRadius * outerRadius) return sand;
    double g = -INFINITY;
    for (const Eigen::Vector2d& nrm : normals) g = std::max(g, d.dot(nrm));
    const double t = std::clamp((g / apothem - 1.0) / rimFraction, 0.0, 1.0);
    return bottom + (sand - bottom) * t;
  }
  double at(const Eigen::Vector2d& x) const {
    const double s = (x - centres.front()).dot(dir) / step;
    const double reach = outerRadius / step + 1;
    const long k0 = std::max(0L, long(std::floor(s - reach)));
    const long k1 = std::min(long(centres.size()) - 1, long(std::ceil(s + reach)));
    double h = sand;
    for (long k = k0; k <= k1; ++k) h = std::min(h, tool(centres[std::size_t(k)], x));
    return h;
  }
  double distanceToStroke(const Eigen::Vector2d& x) const {
    return tin::pointSegmentDistance(x, centres.front(), centres.back());
  }
};

// A grid holding the exact stamped shape at its vertices (a float each), bilinear between.
struct ExactGrid {
  int side = 0;
  double d = 0;
  std::vector<float> h;
  double at(double x, double y) const { return bilinearAt(h, side, d, x, y); }
};

// A grid of 2^n + 1 squared vertices holding the exact stamped shape.
ExactGrid exactGrid(const Scene& scene, const ExactStroke& exact, int n);

}  // namespace ps::bench::sandtin
