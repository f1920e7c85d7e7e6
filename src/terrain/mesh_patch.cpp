#include "terrain/mesh_patch.hpp"

#include <algorithm>
#include <unordered_map>

namespace ps::terrain {

SpliceReport splicePatch(const Mesh& mesh, const MeshPatch& patch, const core::Chart& chart,
                         PatchJoin join, double skirtDepth, Mesh& out) {
  SpliceReport rep;
  const auto inside = [&](std::uint32_t i) {
    return std::binary_search(patch.replaces.begin(), patch.replaces.end(), mesh.gridIndex[i]);
  };
  out.eye = mesh.eye;
  out.gridIndex = mesh.gridIndex;
  out.positions = mesh.positions;
  out.indices.clear();
  out.indices.reserve(mesh.indices.size() + patch.indices.size());
  // Edges of left-out triangles, by their two vertices (low, high): a kept triangle's edge found
  // here is on the hole's border.
  std::unordered_map<std::uint64_t, int> droppedEdges;
  const auto key = [](std::uint32_t a, std::uint32_t b) {
    return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
  };
  std::vector<std::uint32_t> kept;
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const std::uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    if (inside(a) && inside(b) && inside(c)) {
      ++rep.dropped;
      ++droppedEdges[key(a, b)], ++droppedEdges[key(b, c)], ++droppedEdges[key(c, a)];
    } else {
      out.indices.insert(out.indices.end(), {a, b, c});
    }
  }
  // The skirts: each border edge a-b (as its kept triangle runs) walled down by skirtDepth along
  // the chart's up at each end, seen from both sides.
  if (join == PatchJoin::kSkirts && rep.dropped > 0) {
    const int side = chart.grid().side();
    const std::size_t keptEnd = out.indices.size();
    for (std::size_t t = 0; t < keptEnd; t += 3) {
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = out.indices[t + std::size_t(e)];
        const std::uint32_t b = out.indices[t + std::size_t((e + 1) % 3)];
        if (!droppedEdges.count(key(a, b))) continue;
        ++rep.borderEdges;
        const auto lowered = [&](std::uint32_t i) {
          const std::uint64_t g = out.gridIndex[i];
          const Eigen::Vector3d up =
              chart.up(int(g % std::uint64_t(side)), int(g / std::uint64_t(side)));
          out.gridIndex.push_back(g);
          out.positions.push_back(out.positions[i] - (skirtDepth * up).cast<float>());
          return std::uint32_t(out.positions.size() - 1);
        };
        const std::uint32_t a2 = lowered(a), b2 = lowered(b);
        out.indices.insert(out.indices.end(), {a, a2, b, b, a2, b2, b, a2, a, b2, a2, b});
        rep.skirtTriangles += 4;
      }
    }
  }
  // The patch's vertices after the view's.
  const auto base = std::uint32_t(out.positions.size());
  out.patchVertexBegin = base;
  out.patchIndexBegin = out.indices.size();
  out.patchHeights.clear();
  for (std::size_t i = 0; i < patch.positions.size(); ++i) {
    out.positions.push_back((patch.positions[i] - mesh.eye).cast<float>());
    out.gridIndex.push_back(patch.gridIndex[i]);
    out.patchHeights.push_back(float(patch.heights[i]));
  }
  for (const std::uint32_t i : patch.indices) out.indices.push_back(base + i);
  rep.patchTriangles = patch.indices.size() / 3;
  out.generation = nextMeshGeneration();
  return rep;
}

const Mesh& SplicedView::view(const Mesh& mesh, std::shared_ptr<const MeshPatch> patch,
                              const core::Chart& chart, PatchJoin join, double skirtDepth) {
  if (!patch) {
    patch_.reset();
    mesh_ = nullptr;
    return mesh;
  }
  if (patch != patch_ || mesh_ != &mesh || meshGeneration_ != mesh.generation || join != join_ ||
      skirtDepth != skirtDepth_) {
    report_ = splicePatch(mesh, *patch, chart, join, skirtDepth, out_);
    patch_ = std::move(patch);
    mesh_ = &mesh;
    meshGeneration_ = mesh.generation;
    join_ = join;
    skirtDepth_ = skirtDepth;
  }
  return out_;
}

}  // namespace ps::terrain
