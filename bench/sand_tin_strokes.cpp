#include "bench/sand_tin_strokes.hpp"

#include "bench/bench_util.hpp"
#include "sand/material.hpp"
#include "sand/sand_field.hpp"
#include "sand/sand_grid.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::bench::sandtin {

tin::DynamicTin flatTin(const Scene& scene, int n) {
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      points.emplace_back(scene.side * i / (n - 1), scene.side * j / (n - 1), scene.sand);
  return tin::DynamicTin(points);
}

double maxEdgeSlope(const tin::DynamicTin& t) {
  double worst = 0;
  std::vector<tin::DynamicTin::Vertex> nb;
  for (const auto v : t.vertices()) {
    t.neighbours(v, nb);
    for (const auto u : nb)
      worst = std::max(
          worst, std::abs(t.height(u) - t.height(v)) / (t.position(u) - t.position(v)).norm());
  }
  return worst;
}

TinRun runTin(const Scene& scene, int n, double trace, bool erosion, bool pushAside) {
  TinRun run;
  run.sand = std::make_unique<sand::TinSand>(flatTin(scene, n));
  const double v0 = run.sand->tin().volume();
  sand::TinStampTool tool = sand::TinStampTool::disc(scene.radius);
  tool.pushAside = pushAside;
  run.ms = timeMs([&] {
    for (const Eigen::Vector2d& c : scene.stroke(trace)) {
      run.sand->stamp(c, scene.bottom(), tool);
      ++run.stamps;
      if (!erosion) continue;
      for (int s = 0; s < scene.erosionSteps; ++s) run.sand->erode(), ++run.erosionSteps;
      run.removed += run.sand->removeRedundant();
    }
  });
  run.drift = std::abs(run.sand->tin().volume() - v0) / v0;
  return run;
}

namespace {

void gridStamp(GridRun& g, const Scene& scene, const sand::TinStampTool& tool,
               const Eigen::Vector2d& c, terrain::VertexBox& touched) {
  const double d = g.chart->dx(), area = d * d;
  const double outer = tool.outerRadius(), reach = tool.reach();
  // Inside the outline (a polygon about c; crossing number).
  const auto pressed = [&](const Eigen::Vector2d& p) {
    bool inside = false;
    const std::size_t n = tool.outline.size();
    for (std::size_t a = 0, b = n - 1; a < n; b = a++) {
      const Eigen::Vector2d pa = c + tool.outline[a], pb = c + tool.outline[b];
      if ((pa.y() > p.y()) != (pb.y() > p.y()) &&
          p.x() < (pb.x() - pa.x()) * (p.y() - pa.y()) / (pb.y() - pa.y()) + pa.x())
        inside = !inside;
    }
    return inside;
  };
  const int i0 = std::max(0, int((c.x() - reach) / d) - 1),
            i1 = std::min(g.side - 1, int((c.x() + reach) / d) + 1);
  const int j0 = std::max(0, int((c.y() - reach) / d) - 1),
            j1 = std::min(g.side - 1, int((c.y() + reach) / d) + 1);
  double displaced = 0, weighted = 0;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      float& h = g.heights[std::size_t(j) * g.side + i];
      const Eigen::Vector2d p(i * d, j * d);
      const double r = (p - c).norm();
      if (pressed(p)) {
        // The bottom as a float: what is pressed out is then exactly what the floats lose.
        const float bottom = float(scene.bottom());
        if (h > bottom) displaced += area * (double(h) - bottom), h = bottom;
      } else {
        const double t = std::clamp((r - outer) / tool.rampartWidth, 0.0, 1.0);
        weighted += area * (1 - 3 * t * t + 2 * t * t * t) * (r <= reach);
      }
    }
  double carry = 0;
  if (weighted > 0)
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Eigen::Vector2d p(i * d, j * d);
        const double r = (p - c).norm();
        if (pressed(p) || r > reach) continue;
        const double t = std::clamp((r - outer) / tool.rampartWidth, 0.0, 1.0);
        float& h = g.heights[std::size_t(j) * g.side + i];
        // Rounded with the residual carried on, as the grid core's displacement tool does.
        const double exact = h + displaced / weighted * (1 - 3 * t * t + 2 * t * t * t);
        const float f = float(exact + carry / area);
        carry += area * (exact - double(f));
        h = f;
      }
  touched = {i0, i1, j0, j1};
}

}  // namespace

GridRun runGrid(const Scene& scene, int n, double trace, bool erosion) {
  GridRun g;
  const core::GridSize size(n);
  g.side = size.side();
  g.chart =
      std::make_shared<core::FlatChart>(size, scene.side / (g.side - 1), scene.side / (g.side - 1));
  g.heights.assign(std::size_t(g.side) * g.side, float(scene.sand));
  const sand::SandGrid grid(g.chart);
  const double v0 = grid.volume(g.heights);
  sand::SandField field(g.chart, g.heights);
  const sand::TinStampTool tool = sand::TinStampTool::disc(scene.radius);
  const sand::Material material = sand::Material::sand();
  std::size_t resident = 0;
  g.ms = timeMs([&] {
    for (const Eigen::Vector2d& c : scene.stroke(trace)) {
      terrain::VertexBox touched;
      g.stampMs += timeMs([&] {
        field.writeBack(1e9);
        gridStamp(g, scene, tool, c, touched);
        field.mark(touched);
      });
      ++g.stamps;
      if (!erosion) continue;
      g.erodeMs += timeMs([&] {
        for (int s = 0; s < scene.erosionSteps; ++s) field.thermalStep(material), ++g.erosionSteps;
      });
      resident = std::max(resident, field.residentBytes());
    }
    field.writeBack(1e9);
  });
  g.memory = g.heights.size() * sizeof(float) + resident;
  g.drift = std::abs(grid.volume(g.heights) - v0) / v0;
  return g;
}

double gridSteepest(const GridRun& g) {
  const double d = g.chart->dx();
  double worst = 0;
  for (int j = 0; j < g.side; ++j)
    for (int i = 0; i < g.side; ++i) {
      const double h = g.heights[std::size_t(j) * g.side + i];
      if (i + 1 < g.side)
        worst = std::max(worst, std::abs(g.heights[std::size_t(j) * g.side + i + 1] - h) / d);
      if (j + 1 < g.side)
        worst = std::max(worst, std::abs(g.heights[std::size_t(j + 1) * g.side + i] - h) / d);
    }
  return worst;
}

ExactGrid exactGrid(const Scene& scene, const ExactStroke& exact, int n) {
  ExactGrid g;
  g.side = core::GridSize(n).side();
  g.d = scene.side / (g.side - 1);
  g.h.assign(std::size_t(g.side) * g.side, float(scene.sand));
  for (const Eigen::Vector2d& c : exact.centres) {
    const int i0 = std::max(0, int((c.x() - exact.outerRadius) / g.d)),
              i1 = std::min(g.side - 1, int((c.x() + exact.outerRadius) / g.d) + 1);
    const int j0 = std::max(0, int((c.y() - exact.outerRadius) / g.d)),
              j1 = std::min(g.side - 1, int((c.y() + exact.outerRadius) / g.d) + 1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        float& h = g.h[std::size_t(j) * g.side + i];
        h = std::min(h, float(exact.tool(c, {i * g.d, j * g.d})));
      }
  }
  return g;
}

}  // namespace ps::bench::sandtin
