#pragma once
// The project's one triangulation layer: CGAL's constrained Delaunay triangulation (EPICK
// kernel: exact predicates, so the triangulation is valid whatever the coordinates) with the
// vertex and face bases Delaunay_mesher_2 needs, and a height on every vertex. The TIN export
// (tin_mesher) builds on it; the sand TIN will too. Include it only from .cpp files: CGAL's
// templates are slow to compile, and nothing outside this layer needs to see them.
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_Delaunay_triangulation_face_base_2.h>
#include <CGAL/Constrained_triangulation_face_base_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <cmath>
#include <cstdint>

namespace ps::tin {

struct VertexData {
  double height = NAN;      // NaN until known (a Steiner point's is taken when first needed)
  std::uint32_t index = 0;  // scratch: the vertex's number when a TIN is written out
};

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Delaunay_mesh_vertex_base_2<
    Kernel, CGAL::Triangulation_vertex_base_with_info_2<VertexData, Kernel>>;
using FaceBase = CGAL::Delaunay_mesh_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Exact_predicates_tag: constraints may cross (roads over break lines); their intersections
// are constructed in doubles.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_predicates_tag>;
using Point = Cdt::Point;
using VertexHandle = Cdt::Vertex_handle;
using FaceHandle = Cdt::Face_handle;

// The same triangulation without the mesher's bases, for TINs that are never refined (the sand
// TIN, tin/dynamic_tin): 40-byte vertices and 56-byte faces instead of 48 and 88. The face is
// the plain constrained one (CGAL's default for a constrained Delaunay triangulation): the
// Delaunay face base's blinding edge and flag (24 bytes) serve only the mesher's visibility.
namespace lean {
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<VertexData, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_predicates_tag>;
using VertexHandle = Cdt::Vertex_handle;
using FaceHandle = Cdt::Face_handle;
}  // namespace lean

}  // namespace ps::tin
