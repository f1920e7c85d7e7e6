#pragma once
// A surface patch drawn in place of part of a tessellated view (the TIN sand tool's region TIN
// at its own detail): the view's triangles whose three vertices the patch replaces are left
// out, the patch's triangles go in, and the join is closed.
//
// Why the join can leak: the patch covers the hole it makes (the triangles left out have every
// vertex inside the patch's convex domain, so they lie in it), but along the hole's border the
// view's kept triangles and the patch are two surfaces that agree only to the view's error and
// the patch's tolerance. A line of sight that passes over a kept triangle's border edge and
// under the patch (where the patch lies lower there) meets neither: background. Skirts close
// that: from every border edge of the hole a wall hangs `skirtDepth` metres down (both
// windings), so such a line meets the wall.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/chart.hpp"
#include "terrain/mesh.hpp"

namespace ps::terrain {

// Outside MeshPatch because clang 14 cannot default-construct a nested struct with member
// initialisers inside std::optional of the enclosing class. The plane the surface is a height field
// over, where it has one (the sand TIN's tangent plane): the haptic path feels the surface there by
// the patch's own interpolation (linear in (x, y) per triangle) rather than by the planar facets
// drawn between `positions`.
struct PatchPlane {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero(), east = Eigen::Vector3d::UnitX(),
                  north = Eigen::Vector3d::UnitY(), up = Eigen::Vector3d::UnitZ();
  // > 0: a sphere about the planet frame's origin, (x, y) the orthographic projection of the
  // point on it; 0: a flat chart, (x, y) along east and north from `origin`.
  double radius = 0;
};

struct MeshPatch {
  std::vector<Eigen::Vector3d> positions;  // planet frame
  std::vector<std::uint64_t> gridIndex;    // per vertex: the nearest grid vertex (shading lookups)
  std::vector<double> heights;             // per vertex: metres above the reference surface
  std::vector<std::uint32_t> indices;      // 3 per triangle, counter-clockwise from outside
  std::vector<std::uint64_t> replaces;     // sorted grid indices (v * side + u) it stands for
  using Plane = PatchPlane;
  std::optional<Plane> plane;
  std::vector<Eigen::Vector2d> xy;  // per vertex, in `plane` (empty without one)
};

enum class PatchJoin { kNone, kSkirts };

struct SpliceReport {
  std::size_t dropped = 0;         // view triangles left out
  std::size_t patchTriangles = 0;  // patch triangles added
  std::size_t borderEdges = 0;     // edges between a kept and a left-out view triangle
  std::size_t skirtTriangles = 0;
};

// `out` = `mesh` with the patch spliced in (positions relative to mesh.eye; a new generation).
// The view's vertices stay first and in order, so `out` draws every kept triangle as `mesh` did.
SpliceReport splicePatch(const Mesh& mesh, const MeshPatch& patch, const core::Chart& chart,
                         PatchJoin join, double skirtDepth, Mesh& out);

// What a renderer draws: the view's mesh with a patch spliced in, spliced again only when the
// view's mesh (its generation) or the patch (another object) changed, so an unchanged view
// keeps its generation and is not uploaded again.
class SplicedView {
 public:
  // `mesh` itself when `patch` is null; else the spliced mesh, held until the next call.
  const Mesh& view(const Mesh& mesh, std::shared_ptr<const MeshPatch> patch,
                   const core::Chart& chart, PatchJoin join = PatchJoin::kNone,
                   double skirtDepth = 0);
  const SpliceReport& report() const { return report_; }  // of the last splice

 private:
  Mesh out_;
  std::shared_ptr<const MeshPatch> patch_;
  const Mesh* mesh_ = nullptr;
  std::uint64_t meshGeneration_ = 0;
  PatchJoin join_ = PatchJoin::kNone;
  double skirtDepth_ = 0;
  SpliceReport report_;
};

}  // namespace ps::terrain
