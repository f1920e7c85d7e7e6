#pragma once
// Roads onto a terrain TIN (paper 001, section 4): a road is any triangle mesh laid on the ground
// (a road, a path, a runway), placed in the terrain's lattice coordinates.
//
//   stitch: every edge of both meshes is kept, split where they cross (CGAL's constrained
//     triangulation with intersecting constraints); each vertex the road brings or the crossings
//     make lies on the terrain mesh (its position is the terrain triangle's own blend of its
//     corners), so the terrain's surface is unchanged: zero height error. On a planet the road
//     is draped over the mesh first (tin/road_drape.hpp); a sphere's stitch goes in the road's
//     own plane instead where it can (tin/plane_stitch.hpp, io/overlay_export.cpp).
//   stencil: the road's vertices, edges and heights are kept; the terrain's vertices under it
//     are removed, and the terrain around it is meshed again by greedy insertion to the error,
//     every sample outside the footprint measured.
//
// A road that leaves the lattice is clipped at its border (its triangles cut there, new
// vertices' heights interpolated on the road).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "tin/sample_field.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::tin {

struct Road {
  std::vector<Eigen::Vector2d> xy;  // lattice coordinates
  std::vector<double> h;            // heights (stencil keeps them; stitch takes the terrain's)
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

enum class OverlayMode { kStitch, kStencil };

struct OverlayReport {
  std::size_t terrainVertices = 0, roadVertices = 0, roadTriangles = 0;
  std::size_t clippedRoadTriangles = 0;    // cut at (or dropped beyond) the lattice's border
  std::size_t crossingVertices = 0;        // stitch: where a road edge crosses a terrain edge
  std::size_t removedTerrainVertices = 0;  // stencil: under the footprint
  std::size_t refillVertices = 0;          // stencil: inserted again around the footprint
  // stitch: the largest distance of a vertex the overlay added from the terrain mesh (0 up to
  // rounding); stencil: the largest distance, over samples inside the footprint, of the road's
  // surface from the result's (0 up to rounding: the road's triangles are the result's there).
  double addedVertexErrorM = 0;
  double footprintErrorM = 0;
  // stencil: the largest error / tolerance over samples outside the footprint (<= 1).
  double outsideErrorRatio = 0;
  // stitch on a planet (tin/road_drape.hpp): edges laid along the mesh, edges left straight
  // (their walk left the mesh), and the farthest the drape moved a road vertex's point.
  std::size_t drapedEdges = 0, undrapedEdges = 0;
  double drapeMoveM = 0;
};

struct OverlayResult {
  Tin tin;                                 // lattice coordinates; h as written for samples
  std::vector<Eigen::Vector3d> positions;  // each vertex in the output frame (metres)
  std::vector<std::uint8_t> onRoad;        // per triangle: inside the road's footprint
  OverlayReport report;
};

// `terrain` is the terrain's TIN (buildTin on `field`); `field.uniformTolerance` is the error
// the stencil's re-meshing keeps outside the footprint. Throws core::InputError for a road
// that crosses itself, overlaps itself, has degenerate triangles, or lies wholly outside.
OverlayResult overlayRoad(const SampleField& field, const Tin& terrain, const Road& road,
                          OverlayMode mode);

}  // namespace ps::tin
