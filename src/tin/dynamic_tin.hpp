#pragma once
// A TIN that changes: vertices inserted, moved up and down, removed; edges constrained and
// freed again. The sand TIN (sand/tin_sand, paper 000) works on it; the triangulation is the
// layer's one CDT (tin/cdt.hpp), kept behind this interface so that CGAL stays private.
//
// Vertices have stable numbers (a removed vertex's number is given to a later one). The domain
// is the convex hull of the starting points (a rectangle for a terrain tile); hull vertices are
// never removed, so the domain never shrinks.
//
// Volume: V = integral of the piecewise-linear surface h(x, y) over the domain, above the base
// plane h = 0 (signed). It equals sum_v h_v w_v with w_v = (area of v's triangles) / 3, so a
// vertex raised by dh adds exactly w_v dh: moving material between vertices in those units
// keeps V while the triangulation stays, and what a change of triangulation does to V is
// measured and can be put back.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "tin/tin_mesher.hpp"

namespace ps::tin {

class DynamicTin {
 public:
  using Vertex = std::uint32_t;
  static constexpr Vertex kNoVertex = ~Vertex(0);

  // The Delaunay triangulation of `points` (x, y, height). Throws core::InputError when fewer
  // than three are not collinear or a coordinate is not finite.
  explicit DynamicTin(std::span<const Eigen::Vector3d> points);
  ~DynamicTin();
  DynamicTin(DynamicTin&&) noexcept;
  DynamicTin& operator=(DynamicTin&&) noexcept;

  std::size_t vertexCount() const;
  std::size_t triangleCount() const;
  std::size_t constrainedEdgeCount() const;
  // Changes whenever the triangulation does (not when only heights do): what depends on it
  // alone, such as weights, can be cached until it changes.
  std::uint64_t topologyEpoch() const;
  // Bytes the triangulation holds (its vertex and face containers' capacity, and the id table).
  std::size_t memoryBytes() const;
  // The vertex and face containers' slots (capacity: live elements, freed ones kept for reuse,
  // and the growth reserve) and their live elements (the infinite vertex and its faces included).
  struct Slots {
    std::size_t vertexSlots = 0, vertices = 0, faceSlots = 0, faces = 0;
  };
  Slots slots() const;

  bool alive(Vertex v) const;
  Eigen::Vector2d position(Vertex v) const;
  double height(Vertex v) const;
  void setHeight(Vertex v, double h);
  bool onHull(Vertex v) const;
  // v's neighbours, counter-clockwise.
  void neighbours(Vertex v, std::vector<Vertex>& out) const;
  // The same with each neighbour's position and height, in one walk around v (erosion's inner
  // loop: no lookup by number per neighbour).
  struct Neighbour {
    Vertex v;
    Eigen::Vector2d p;
    double h;
  };
  void neighbourhood(Vertex v, std::vector<Neighbour>& out) const;
  // w_v: the volume a metre of height at v adds (a third of the area of its triangles).
  double weight(Vertex v) const;
  // Every live vertex, in number order.
  std::vector<Vertex> vertices() const;
  // The vertices within `radius` of `centre` (found by walking from the triangle there).
  void verticesWithin(const Eigen::Vector2d& centre, double radius, std::vector<Vertex>& out) const;

  bool contains(const Eigen::Vector2d& p) const;
  // How far p lies inside the domain: the distance to its border, negative outside.
  double depthInside(const Eigen::Vector2d& p) const;
  // For each point, depthInside(p) >= depth, answered for many points at once: the border's
  // edges are bucketed once (each in the cells of `depth` its box reaches), so a point checks
  // the few edges near it, not the whole border; point location walks from the last point's
  // triangle (points in a sensible order, such as grid order, walk a few triangles each).
  std::vector<std::uint8_t> deeperThan(std::span<const Eigen::Vector2d> points, double depth) const;
  // The surface's height at p (NaN outside the domain): point location walks from the last
  // triangle found, as the paper's rectangular walk does.
  double heightAt(const Eigen::Vector2d& p) const;

  // A vertex within `radius` of p among those of the triangle over p and its neighbours (the
  // nearest of them), or kNoVertex: inserting again next to a vertex would leave a sliver.
  Vertex vertexNear(const Eigen::Vector2d& p, double radius) const;

  // A vertex at p with height h (an existing vertex there keeps its number and takes h). p must
  // lie in the domain.
  Vertex insert(const Eigen::Vector2d& p, double h);
  // A vertex at p on the surface (its height interpolated: the surface stays, the
  // triangulation's flips around it may change the volume).
  Vertex insertOnSurface(const Eigen::Vector2d& p);

  // The edge a-b constrained (it must not cross a constrained edge; the caller frees those
  // first), tagged with the generation of the stamp that made it.
  void constrain(Vertex a, Vertex b, std::uint32_t generation);
  // Constrained edges with a point within `radius` of `centre` become free (the triangulation
  // is made Delaunay again there). Returns how many.
  // The freed edges' ends (x, y, height) go to *freed when given.
  std::size_t freeConstraintsNear(
      const Eigen::Vector2d& centre, double radius,
      std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>* freed = nullptr);
  // The generation of the constrained edge a-b; kNoVertex when it is not constrained.
  std::uint32_t generation(Vertex a, Vertex b) const;

  // Removes v (freeing its constrained edges first) and re-fills the hole with Delaunay
  // triangles; false (nothing changed) for a hull vertex. The volume re-filling changed is put
  // back by raising the hole's rim vertices alike (so V is kept to rounding; not when
  // restoreVolume is false: a caller that measures V itself); the change before that is
  // returned in *volumeChange.
  bool remove(Vertex v, double* volumeChange = nullptr, bool restoreVolume = true);

  // V (see above), summed over the triangles in long double.
  double volume() const;
  // CGAL's own validity check of the triangulation, and every height finite.
  bool isValid() const;
  // What is wrong when isValid() is false ("" when it is true).
  std::string validityProblem() const;
  // The triangles as a Tin (positions in the TIN's own units, counter-clockwise).
  Tin toTin() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ps::tin
