#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::terrain {

// View-independent mesh of the whole planet: a triangle splits while its split vertex's error
// bound exceeds maxErrorMetres. Crack-free for the same reason as the view-dependent mesh (the
// errors are nested), and the true 3D deviation of every full-resolution vertex from the mesh
// is at most maxErrorMetres. Positions are relative to the planet's centre (Mesh::eye = 0).
//
// An ErrorMesher keeps its grid-to-vertex table between calls, and mesh() refills the caller's
// Mesh in place: re-meshing (an export sweep, a live preview) then touches no fresh memory. On
// this project's VM a fresh 4 KiB page costs about 10 us to fault in, which was most of a
// one-shot mesh pass. One mesher per thread: mesh() writes its table.
class ErrorMesher {
 public:
  // Throws core::InputError for a negative or non-finite maxErrorMetres (`out` is then untouched).
  void mesh(const Terrain& terrain, double maxErrorMetres, Mesh& out);

  // Grid index -> mesh vertex, in pages of 64 Ki entries made when first touched: as fast as a
  // flat array (a hash map cost half the mesher's time) without a 1 GB table for a 16385² grid
  // when the mesh is coarse. Every slot a mesh sets is reset before mesh() returns.
  class VertexIndex {
   public:
    static constexpr std::uint32_t kNone = 0xffffffffu;
    void prepare(std::uint64_t gridCount);  // sizes for a grid; drops the pages if it changed
    std::uint32_t& operator[](std::uint64_t gi) {
      auto& page = pages_[gi >> kPageBits];
      if (!page) page = freshPage();
      return page[gi & (kPageSize - 1)];
    }
    void reset(const std::vector<std::uint64_t>& used);

   private:
    static constexpr int kPageBits = 16;
    static constexpr std::size_t kPageSize = std::size_t(1) << kPageBits;
    static std::unique_ptr<std::uint32_t[]> freshPage();
    std::uint64_t gridCount_ = 0;
    std::vector<std::unique_ptr<std::uint32_t[]>> pages_;
  };

 private:
  VertexIndex vertexOf_;
};

// One-shot form of ErrorMesher::mesh.
Mesh meshToError(const Terrain& terrain, double maxErrorMetres);

}  // namespace ps::terrain
