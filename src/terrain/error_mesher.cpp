#include "terrain/error_mesher.hpp"

#include <cmath>
#include <unordered_map>

#include "core/input_error.hpp"
#include "terrain/diamond.hpp"

namespace ps::terrain {

Mesh meshToError(const Terrain& terrain, double maxErrorMetres) {
  if (!std::isfinite(maxErrorMetres) || maxErrorMetres < 0) {
    throw core::InputError("maximum error " + std::to_string(maxErrorMetres) +
                           " m must be finite and >= 0");
  }
  const core::GridSize g = terrain.grid();
  const int m = g.m();
  const auto& codes = terrain.bounds().codes();
  Mesh mesh;
  std::unordered_map<std::uint64_t, std::uint32_t> vertexOf;
  auto vertex = [&](GridPoint p) {
    const std::uint64_t gi = g.index(p.u, p.v);
    auto [it, fresh] = vertexOf.try_emplace(gi, std::uint32_t(mesh.gridIndex.size()));
    if (fresh) {
      mesh.gridIndex.push_back(gi);
      mesh.positions.push_back(
          terrain.chart().position(p.u, p.v, terrain.height(p.u, p.v)).cast<float>());
    }
    return it->second;
  };
  struct Tri {
    GridPoint a, b0, b1;
  };
  std::vector<Tri> stack = {{{0, m}, {0, 0}, {m, m}}, {{m, 0}, {m, m}, {0, 0}}};
  while (!stack.empty()) {
    const Tri t = stack.back();
    stack.pop_back();
    const int su = t.b0.u + t.b1.u, sv = t.b0.v + t.b1.v;
    if (((su | sv) & 1) == 0) {
      const GridPoint c{su / 2, sv / 2};
      if (double(BoundCode::decode(codes[g.index(c.u, c.v)].error)) > maxErrorMetres) {
        stack.push_back({c, t.b1, t.a});
        stack.push_back({c, t.a, t.b0});
        continue;
      }
    }
    mesh.indices.push_back(vertex(t.a));
    mesh.indices.push_back(vertex(t.b0));
    mesh.indices.push_back(vertex(t.b1));
  }
  return mesh;
}

}  // namespace ps::terrain
