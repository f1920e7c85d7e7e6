#pragma once
// Helpers shared by the edit tests (tests/test_edit_*.cpp).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/latlong_chart.hpp"
#include "edit/brush.hpp"
#include "edit/distance_field.hpp"
#include "edit/edit_pipeline.hpp"
#include "edit/region_growing.hpp"
#include "terrain/terrain.hpp"
#include "test_terrains.hpp"

namespace ps::edittest {

// The lat-long geometry behind a chart that is not a LatLongChart: drives the edit layer's
// generic (any chart) paths on a seamed chart with poles.
class OpaqueChart final : public core::Chart {
 public:
  explicit OpaqueChart(std::shared_ptr<const core::LatLongChart> c)
      : Chart(c->grid()), c_(std::move(c)) {}
  std::string name() const override { return "opaque-latlong"; }
  Eigen::Vector3d position(int u, int v, double h) const override { return c_->position(u, v, h); }
  Eigen::Vector3d up(int u, int v) const override { return c_->up(u, v); }
  Eigen::Vector3d positionAt(double u, double v, double h) const override {
    return c_->positionAt(u, v, h);
  }
  std::optional<Eigen::Vector2d> inverse(const Eigen::Vector3d& p) const override {
    return c_->inverse(p);
  }
  bool wrapsU() const override { return true; }
  bool hasPoleRows() const override { return true; }
  double sphereRadius() const override { return c_->sphereRadius(); }

 private:
  std::shared_ptr<const core::LatLongChart> c_;
};

// A centre anywhere, biased to the hard places: poles, the seam, next to the poles.
inline core::GridPoint randomCentre(std::mt19937& rng, int m) {
  const int kind = int(rng() % 7);
  const int u = int(rng() % unsigned(m + 1)), v = int(rng() % unsigned(m + 1));
  const int near = 1 + int(rng() % 3);
  switch (kind) {
    case 0:
      return {u, (rng() & 1) ? 0 : m};  // a pole (any u: the whole row is one point)
    case 1:
      return {(rng() & 1) ? 0 : m, v};  // the seam, either twin
    case 2:
      return {u, (rng() & 1) ? near : m - near};  // next to a pole
    case 3:
      return {(rng() & 1) ? 0 : m, (rng() & 1) ? near : m - near};  // seam next to a pole
    default:
      return {u, v};
  }
}

// Log-uniform from 0.3 cell to beyond the diameter, sometimes exactly the diameter.
inline double randomRadius(std::mt19937& rng, double R, int m) {
  const double cell = std::numbers::pi * R / m;
  if (rng() % 12 == 0) return 2.0 * R;
  std::uniform_real_distribution<double> e(std::log(0.3 * cell), std::log(2.05 * R));
  return std::exp(e(rng));
}

// Region == brute force, entry by entry.
inline ::testing::AssertionResult equalsBruteForce(const edit::DistanceField& field, double radius,
                                                   const edit::Region& region) {
  std::vector<std::uint8_t> mask;
  const std::size_t count = edit::bruteForceRegion(field, radius, &mask);
  const core::GridSize g = field.grid();
  if (count != region.vertexCount()) {
    return ::testing::AssertionFailure()
           << "brute force " << count << " vertices, region " << region.vertexCount();
  }
  for (int v = 0; v <= g.m(); ++v) {
    for (int u = 0; u <= g.m(); ++u) {
      if (bool(mask[g.index(u, v)]) != region.contains(u, v)) {
        return ::testing::AssertionFailure()
               << "vertex (" << u << "," << v << ") brute force " << int(mask[g.index(u, v)])
               << " region " << region.contains(u, v);
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Every grid vertex of one surface point (the chart's canonical vertex: seam twins, a pole row,
// a folded side's mirror) holds the same bits; everything finite and within the limit.
inline ::testing::AssertionResult consistentHeights(const terrain::Terrain& t) {
  const auto g = t.grid();
  const int m = g.m();
  const auto h = t.heights();
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const float x = h[g.index(u, v)];
      if (!std::isfinite(x) || std::abs(double(x)) > t.heightLimit()) {
        return ::testing::AssertionFailure() << "height " << x << " at (" << u << "," << v << ")";
      }
      const core::GridPoint c = t.chart().canonical(u, v);
      if (std::memcmp(&h[g.index(u, v)], &h[g.index(c.u, c.v)], sizeof(float)) != 0) {
        return ::testing::AssertionFailure() << "(" << u << "," << v << ") differs from (" << c.u
                                             << "," << c.v << "), the same point";
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Every lattice vertex (half-size >= 2^kLatticeShift, where the tessellator reads it) holds the
// height and codes the full arrays hold: twins across a fold or a seam their combined codes.
// (Glued twins once held each its own half's there, equal in a build and an update alike.)
inline ::testing::AssertionResult latticeHoldsTheCodes(const terrain::Terrain& t) {
  const terrain::ErrorBounds& b = t.bounds();
  if (b.lattice().empty()) return ::testing::AssertionSuccess();
  const int m = t.grid().m();
  for (int v = 0; v <= m; ++v)
    for (int u = 0; u <= m; ++u) {
      if ((u == 0 || u == m) && (v == 0 || v == m)) continue;  // corners split nothing
      if (std::countr_zero(unsigned(u | v)) < terrain::ErrorBounds::kLatticeShift) continue;
      const terrain::LatticeEntry& e = b.lattice()[b.latticeIndex(u, v)];
      const terrain::BoundCodes& c = b.codes()[t.grid().index(u, v)];
      if (!(e.codes == c) || e.height != t.height(u, v))
        return ::testing::AssertionFailure()
               << "lattice vertex (" << u << "," << v << ") holds error/radius codes "
               << e.codes.error << "/" << e.codes.radius << ", the full arrays " << c.error << "/"
               << c.radius;
    }
  return ::testing::AssertionSuccess();
}

// Bounds after the local updates == a full rebuild, bit for bit.
inline ::testing::AssertionResult boundsEqualFullRebuild(const terrain::Terrain& t) {
  if (auto held = latticeHoldsTheCodes(t); !held) return held;
  terrain::ErrorBounds full;
  full.build(t.chart(), t.heights(), t.bounds().rule());
  if (full.errorCodes() != t.bounds().errorCodes()) {
    return ::testing::AssertionFailure() << "error codes differ from a full rebuild";
  }
  if (full.radiusCodes() != t.bounds().radiusCodes()) {
    return ::testing::AssertionFailure() << "radius codes differ from a full rebuild";
  }
  if (!(full.lattice() == t.bounds().lattice())) {
    return ::testing::AssertionFailure() << "the tessellator's lattice differs from a full rebuild";
  }
  return ::testing::AssertionSuccess();
}

inline bool sameBits(std::span<const float> a, std::span<const float> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// A point of the planet frame at latitude/longitude (degrees) and altitude factor k (|p| = kR).
inline Eigen::Vector3d latLon(double latDeg, double lonDeg, double R, double k = 1.0) {
  const double la = latDeg * std::numbers::pi / 180, lo = lonDeg * std::numbers::pi / 180;
  return k * R *
         Eigen::Vector3d(std::cos(lo) * std::cos(la), std::sin(lo) * std::cos(la), std::sin(la));
}

// The point h metres above the chart's sphere at (latDeg, lonDeg).
inline Eigen::Vector3d pointAbove(const core::Chart& chart, double latDeg, double lonDeg,
                                  double h) {
  return latLon(latDeg, lonDeg, chart.sphereRadius() + h, 1.0);
}

// A random stroke: a single stamp or a few samples, anywhere (poles and seam included).
inline void randomStroke(edit::EditPipeline& pipe, std::mt19937& rng, edit::GaussianBrush& brush) {
  const auto& t = pipe.terrain();
  const int m = t.grid().m();
  edit::BrushSettings s;
  s.radius = 150e3 + 100e3 * double(rng() % 20);
  s.sigma = (rng() & 1) ? 0.17 : 0.75;
  s.mode = edit::BrushMode(rng() % 3);
  s.strength = 100.0 + double(rng() % 3000);
  s.target = 500;
  brush.setSettings(s);
  const core::GridPoint c = randomCentre(rng, m);
  const Eigen::Vector3d p = t.chart().position(c.u, c.v, 0.0);
  if (rng() % 3 == 0) {
    pipe.apply(brush, {p, 0});
    return;
  }
  pipe.beginStroke(brush, {p, 0});
  Eigen::Vector3d q = p;
  for (int k = 0; k < 3; ++k) {
    q = (q + t.chart().sphereRadius() * 0.2 * Eigen::Vector3d::Random()).normalized() *
        t.chart().sphereRadius();
    pipe.moveTo({q, 0.05});
  }
  pipe.endStroke();
}

}  // namespace ps::edittest
