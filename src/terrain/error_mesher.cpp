#include "terrain/error_mesher.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/latlong_chart.hpp"
#include "terrain/diamond.hpp"

namespace ps::terrain {

namespace {

// Asks the kernel for transparent huge pages on the 2 MiB-aligned interior of a freshly
// reserved (untouched) array: one fault per 2 MiB instead of one per 4 KiB. Only a hint; on this
// project's VM a 4 KiB fault costs about 10 us and the faults were most of an export's mesh pass.
template <class T>
void adviseHugePages(const std::vector<T>& v) {
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t end = begin + v.capacity() * sizeof(T);
  const std::uintptr_t a = (begin + kHuge - 1) & ~(kHuge - 1), b = end & ~(kHuge - 1);
  if (b > a) (void)madvise(reinterpret_cast<void*>(a), b - a, MADV_HUGEPAGE);
#else
  (void)v;
#endif
}

// The largest code whose bound is within maxErrorMetres: decode is monotone, so "splits while
// decode(code) > maxErrorMetres" is "splits while code > this", an integer compare per triangle.
std::uint16_t largestCodeWithin(double maxErrorMetres) {
  std::uint16_t code = 0;
  for (int step = 1 << 15; step > 0; step >>= 1) {
    const int next = code + step;
    if (next <= 65535 && double(BoundCode::decode(std::uint16_t(next))) <= maxErrorMetres)
      code = std::uint16_t(next);
  }
  return code;
}

template <class ChartT>
void meshWith(const ChartT& chart, const Terrain& terrain, double maxErrorMetres,
              ErrorMesher::VertexIndex& vertexOf, Mesh& mesh) {
  const core::GridSize g = terrain.grid();
  const int m = g.m();
  const BoundCodes* codes = terrain.bounds().codes().data();
  const float* heights = terrain.heights().data();
  const std::uint16_t within = largestCodeWithin(maxErrorMetres);
  struct Tri {
    GridPoint a, b0, b1;
  };
  // Visits the leaf triangles of the bintree cut at `within`, depth first.
  auto forEachLeaf = [&](auto&& leaf) {
    std::vector<Tri> stack = {{{0, m}, {0, 0}, {m, m}}, {{m, 0}, {m, m}, {0, 0}}};
    while (!stack.empty()) {
      const Tri t = stack.back();
      stack.pop_back();
      const int su = t.b0.u + t.b1.u, sv = t.b0.v + t.b1.v;
      if (((su | sv) & 1) == 0) {
        const GridPoint c{su / 2, sv / 2};
        if (codes[g.index(c.u, c.v)].error > within) {
          stack.push_back({c, t.b1, t.a});
          stack.push_back({c, t.a, t.b0});
          continue;
        }
      }
      leaf(t);
    }
  };
  // Counting first costs one more walk of the codes (about 1 % of an export) and saves the
  // vectors' doublings: on this project's VM, page faults and copies of the growing arrays
  // were two thirds of the mesher's time. Euler on the square: V = (T + B + 2) / 2, B <= 4m.
  std::size_t triangles = 0;
  forEachLeaf([&](const Tri&) { ++triangles; });
  mesh.clear();
  mesh.eye = Eigen::Vector3d::Zero();
  mesh.generation = nextMeshGeneration();
  mesh.indices.reserve(3 * triangles);
  mesh.gridIndex.reserve((triangles + 4 * std::size_t(m) + 2) / 2);
  mesh.positions.reserve((triangles + 4 * std::size_t(m) + 2) / 2);
  adviseHugePages(mesh.indices);
  adviseHugePages(mesh.gridIndex);
  adviseHugePages(mesh.positions);
  vertexOf.prepare(g.count());
  auto vertex = [&](GridPoint p) {
    const std::uint64_t gi = g.index(p.u, p.v);
    std::uint32_t& slot = vertexOf[gi];
    if (slot == ErrorMesher::VertexIndex::kNone) {
      slot = std::uint32_t(mesh.gridIndex.size());
      mesh.gridIndex.push_back(gi);
      mesh.positions.push_back(
          chart.position(p.u, p.v, double(heights[gi])).template cast<float>());
    }
    return slot;
  };
  forEachLeaf([&](const Tri& t) {
    mesh.indices.push_back(vertex(t.a));
    mesh.indices.push_back(vertex(t.b0));
    mesh.indices.push_back(vertex(t.b1));
  });
  vertexOf.reset(mesh.gridIndex);
}

}  // namespace

void ErrorMesher::VertexIndex::prepare(std::uint64_t gridCount) {
  if (gridCount == gridCount_) return;
  pages_.clear();
  pages_.resize((gridCount >> kPageBits) + 1);
  gridCount_ = gridCount;
}

std::unique_ptr<std::uint32_t[]> ErrorMesher::VertexIndex::freshPage() {
  auto page = std::make_unique_for_overwrite<std::uint32_t[]>(kPageSize);
  std::fill_n(page.get(), kPageSize, kNone);
  return page;
}

void ErrorMesher::VertexIndex::reset(const std::vector<std::uint64_t>& used) {
  for (const std::uint64_t gi : used) pages_[gi >> kPageBits][gi & (kPageSize - 1)] = kNone;
}

void ErrorMesher::mesh(const Terrain& terrain, double maxErrorMetres, Mesh& out) {
  if (!std::isfinite(maxErrorMetres) || maxErrorMetres < 0) {
    throw core::InputError("maximum error " + std::to_string(maxErrorMetres) +
                           " m must be finite and >= 0");
  }
  // One dispatch to the concrete chart, so positions inline (a virtual call per vertex else).
  const core::Chart& chart = terrain.chart();
  // A throw part-way (bad_alloc) would leave slots set: start from an empty table then.
  try {
    if (auto* flat = dynamic_cast<const core::FlatChart*>(&chart))
      return meshWith(*flat, terrain, maxErrorMetres, vertexOf_, out);
    if (auto* ll = dynamic_cast<const core::LatLongChart*>(&chart))
      return meshWith(*ll, terrain, maxErrorMetres, vertexOf_, out);
    meshWith(chart, terrain, maxErrorMetres, vertexOf_, out);
  } catch (...) {
    vertexOf_ = VertexIndex{};
    throw;
  }
}

Mesh meshToError(const Terrain& terrain, double maxErrorMetres) {
  Mesh mesh;
  ErrorMesher().mesh(terrain, maxErrorMetres, mesh);
  return mesh;
}

}  // namespace ps::terrain
