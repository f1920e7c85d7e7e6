#pragma once
// Checks of a TIN that do not trust the mesher: its error measured sample by sample (each
// sample located among the TIN's triangles by brute force, not by the mesher's row walk), and
// the welded surface's topology.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "tin/sample_field.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::tin {

struct TinErrorCheck {
  double maxError = 0;  // metres, over every sample
  double maxRatio = 0;  // error / the sample's tolerance, over every sample
  std::int64_t worstSample = -1;
  std::size_t samples = 0;    // samples measured
  std::size_t uncovered = 0;  // samples inside no triangle (must be 0)
};
// `written`, when given, holds each TIN vertex's position as a file stores it (rounded): the
// error is then that of the written mesh (kVertical: its x, y and z; kChart3d: its corners).
TinErrorCheck measureTinError(const SampleField& field, const Tin& tin,
                              std::span<const Eigen::Vector3d> written = {});

// The TIN as a surface: vertices welded where the field's chart makes them one point (seam
// twins, pole rows), triangles that the welding collapsed dropped.
struct WeldedMesh {
  std::vector<std::uint32_t> vertexOf;  // TIN vertex -> welded vertex
  std::size_t vertices = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::uint32_t> sourceTriangle;  // the TIN triangle each one came from
  std::size_t collapsed = 0;                  // TIN triangles dropped (two corners welded into one)
};
WeldedMesh weldTin(const SampleField& field, const Tin& tin);
// The key weldTin joins a TIN vertex at lattice point (x, y) by: its surface point's.
std::pair<double, double> weldKey(const SampleField& field, double x, double y);

struct MeshTopology {
  std::size_t vertices = 0, edges = 0, triangles = 0;
  std::size_t borderEdges = 0;       // used by one triangle
  std::size_t nonManifoldEdges = 0;  // used by three or more, or twice the same way round
  std::size_t degenerate = 0;        // triangles with a repeated vertex
  long long euler() const { return (long long)vertices - (long long)edges + (long long)triangles; }
};
MeshTopology meshTopology(std::size_t vertexCount,
                          const std::vector<std::array<std::uint32_t, 3>>& triangles);

}  // namespace ps::tin
