#include "terrain/screen_error.hpp"

#include <algorithm>
#include <cmath>

#include "terrain/diamond.hpp"

namespace ps::terrain {

namespace {

// Calls f(q_true, q_mesh) for every grid vertex in the triangle (a, b0, b1), right angle at a.
template <class F>
void forEachVertexIn(const Terrain& t, std::uint64_t ia, std::uint64_t ib0, std::uint64_t ib1,
                     F&& f) {
  const core::GridSize g = t.grid();
  const auto side = std::uint64_t(g.side());
  const GridPoint a{int(ia % side), int(ia / side)}, b0{int(ib0 % side), int(ib0 / side)},
      b1{int(ib1 % side), int(ib1 / side)};
  const core::Chart& chart = t.chart();
  auto pos = [&](GridPoint p) { return chart.position(p.u, p.v, double(t.height(p.u, p.v))); };
  const Eigen::Vector3d pa = pos(a), d0 = pos(b0) - pa, d1 = pos(b1) - pa;
  forEachGridPointInTriangle(a, b0, b1, [&](int u, int v, double w0, double w1) {
    f(pos({u, v}), pa + w0 * d0 + w1 * d1);
  });
}

}  // namespace

ScreenErrorReport measureScreenError(const Terrain& terrain, const Camera& camera,
                                     const Mesh& mesh) {
  ScreenErrorReport rep;
  const std::size_t tris = mesh.triangleCount();
  double worst = 0;
  std::size_t checked = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(max : worst) reduction(+ : checked)
  for (std::size_t t = 0; t < tris; ++t) {
    const auto ia = mesh.gridIndex[mesh.indices[3 * t]],
               ib0 = mesh.gridIndex[mesh.indices[3 * t + 1]],
               ib1 = mesh.gridIndex[mesh.indices[3 * t + 2]];
    forEachVertexIn(terrain, ia, ib0, ib1,
                    [&](const Eigen::Vector3d& truth, const Eigen::Vector3d& onMesh) {
                      const Eigen::Vector3d ct = camera.toCamera(truth);
                      if (ct.z() <= 1e-6) return;
                      const Eigen::Vector2d pt = camera.project(ct);
                      if (pt.x() < -0.5 || pt.y() < -0.5 || pt.x() > camera.width - 0.5 ||
                          pt.y() > camera.height - 0.5)
                        return;
                      ++checked;
                      const Eigen::Vector3d cm = camera.toCamera(onMesh);
                      if (cm.z() <= 1e-6) {
                        worst = INFINITY;
                        return;
                      }
                      worst = std::max(worst, (camera.project(cm) - pt).norm());
                    });
  }
  rep.maxPx = worst;
  rep.verticesChecked = checked;
  rep.trianglesChecked = tris;
  return rep;
}

double measureTrueError(const Terrain& terrain, const Mesh& mesh) {
  const std::size_t tris = mesh.triangleCount();
  double worst = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(max : worst)
  for (std::size_t t = 0; t < tris; ++t) {
    forEachVertexIn(terrain, mesh.gridIndex[mesh.indices[3 * t]],
                    mesh.gridIndex[mesh.indices[3 * t + 1]],
                    mesh.gridIndex[mesh.indices[3 * t + 2]],
                    [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
                      worst = std::max(worst, (a - b).norm());
                    });
  }
  return worst;
}

}  // namespace ps::terrain
