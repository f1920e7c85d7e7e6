// The TIN sand tool on the glued charts (issue 43): its region TIN made across the octahedral
// chart's folds and corners and the torus's and the cylinder's seams. On a sand of one depth a
// stamp must do the same wherever it lands: at random grid points, on the folds, the seams and
// the corners, the grid's volume is kept (as on lat-long), every height is finite, twins hold one
// height, and the stamp's radial profile (the volume it moved, ring by ring about its centre)
// equals the profile of the same stamp at a point away from every fold and seam.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/cylinder_chart.hpp"
#include "core/octahedral_chart.hpp"
#include "core/torus_chart.hpp"
#include "edit/edit_pipeline.hpp"
#include "sand/sand_grid.hpp"
#include "sand/stroke_tin.hpp"
#include "sand/tin_sand_tool.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/terrain.hpp"
#include "test_edit_util.hpp"

using namespace ps;

namespace {

constexpr double kDepth = 400.0;  // m of sand everywhere before the stamp

struct StampCase {
  std::string name;
  std::shared_ptr<const core::Chart> chart;
  double radius;  // the stamp's (m)
  // Rows a stamp may sit on (the cylinder's rims are walls: a stamp there is cut by them).
  int vFirst, vLast;
  core::GridPoint reference;             // away from every fold and seam
  std::vector<core::GridPoint> special;  // on folds, seams, corners
};

std::vector<StampCase> stampCases() {
  std::vector<StampCase> out;
  {  // A 20 km sphere, 257^2 (~250 m cells): the lat-long tests' planet and stamp.
    auto c = std::make_shared<core::OctahedralChart>(core::GridSize(8), 20e3);
    const int m = c->grid().m();
    out.push_back({"octahedral",
                   c,
                   1200.0,
                   0,
                   m,
                   {77, 103},
                   // the south pole (the corners), folds on each side, a side's midpoint (a cone
                   // point), the north pole, a crease at the equator
                   {{0, 0},
                    {m, m},
                    {0, 40},
                    {m, 200},
                    {90, 0},
                    {170, m},
                    {0, m / 2},
                    {m / 2, 0},
                    {m / 2, m / 2},
                    {m / 4, m / 4},
                    {2, 1}}});
  }
  {  // R = 2r (the tangent plane's quarter of min(r, R - r) = r is then widest for the cells).
    auto c = std::make_shared<core::TorusChart>(core::GridSize(10), 20e3, 10e3);
    const int m = c->grid().m();
    out.push_back({"torus",
                   c,
                   600.0,
                   0,
                   m,
                   {m / 3, 3 * m / 8},
                   // both seams' crossing, the u seam (outer, top and inner sides), the v seam
                   // (the outer equator)
                   {{0, 0},
                    {m, m},
                    {0, m / 4},
                    {m, m / 2},
                    {0, 3 * m / 4},
                    {m / 5, 0},
                    {m / 2, m},
                    {1, m - 1}}});
  }
  {  // A tube as long as it is round, 257^2 (~123 m cells both ways).
    auto c = std::make_shared<core::CylinderChart>(core::GridSize(8), 5e3, 2 * M_PI * 5e3);
    const int m = c->grid().m();
    out.push_back({"cylinder",
                   c,
                   300.0,
                   12,
                   m - 12,
                   {m / 3, m / 2},
                   {{0, m / 2}, {m, m / 3}, {0, 20}, {1, 2 * m / 3}, {m - 1, m / 2}}});
  }
  return out;
}

// A case's chart under a flat layer kDepth deep, its edit pipeline, a sand tool of the case's
// radius and the grid's cells.
struct SandScene {
  explicit SandScene(const StampCase& c)
      : t(c.chart, std::vector<float>(c.chart->grid().count(), float(kDepth))),
        pipe(t),
        tool(c.chart, settingsOf(c.radius)),
        cells(c.chart) {}
  static sand::TinSandToolSettings settingsOf(double radius) {
    sand::TinSandToolSettings s;
    s.radius = radius;
    return s;
  }
  terrain::Terrain t;
  edit::EditPipeline pipe;
  const sand::TinSandTool tool;
  const sand::SandGrid cells;
};

// What one stamp did: the grid's volume change and the volume moved, ring by ring.
struct StampOutcome {
  double volumeDrift = 0;  // |after - before| / sum A |h|
  double displaced = 0;    // the tool's report (m^3)
  bool consistent = false;
  std::string why;
  std::array<double, 6> rings{};  // sum A (h - kDepth) over chord distance / radius in
                                  // [0, .5), [.5, 1), [1, 1.5), [1.5, 2), [2, 2.5), [2.5, inf)
};

StampOutcome stampAt(terrain::Terrain& t, edit::EditPipeline& pipe, const sand::TinSandTool& tool,
                     const sand::SandGrid& cells, core::GridPoint at, double radius) {
  const core::Chart& chart = t.chart();
  const double before = cells.volume(t.heights());
  // The tool's sphere pressed 150 m into the sand.
  const Eigen::Vector3d centre = chart.position(at.u, at.v, 0.0);
  const Eigen::Vector3d up = chart.up(at.u, at.v);
  pipe.apply(tool, {centre + (kDepth - 150.0 + radius) * up, 0.0});
  StampOutcome o;
  o.volumeDrift = std::abs(cells.volume(t.heights()) - before) / cells.absVolume(t.heights());
  o.displaced = tool.lastStats().displacedVolume;
  const ::testing::AssertionResult same = edittest::consistentHeights(t);
  o.consistent = bool(same);
  if (!same) o.why = same.message();
  const int m = t.grid().m();
  for (int v = 0; v <= m; ++v)
    for (int u = 0; u <= m; ++u) {
      if (!cells.isCell(u, v)) continue;
      const double d = (chart.position(u, v, 0.0) - centre).norm() / radius;
      const std::size_t ring = std::min<std::size_t>(5, std::size_t(d / 0.5));
      o.rings[ring] += cells.cellArea(u, v) * (double(t.height(u, v)) - kDepth);
    }
  return o;
}

// The largest difference between two profiles' rings, relative to the reference's imprint (the
// volume its inner two rings lost).
double profileDifference(const StampOutcome& a, const StampOutcome& ref) {
  const double scale = -(ref.rings[0] + ref.rings[1]);
  double worst = 0;
  for (std::size_t k = 0; k < a.rings.size(); ++k)
    worst = std::max(worst, std::abs(a.rings[k] - ref.rings[k]) / scale);
  return worst;
}

TEST(TinSandGlued, AStampAcrossAFoldOrASeamKeepsVolumeTwinsAndItsProfile) {
  std::mt19937 rng(43);
  for (const StampCase& c : stampCases()) {
    SCOPED_TRACE(c.name);
    terrain::Terrain t(c.chart, std::vector<float>(c.chart->grid().count(), float(kDepth)));
    edit::EditPipeline pipe(t);
    sand::TinSandToolSettings s;
    s.radius = c.radius;  // the region: 5 radii, at most a quarter of the curvature radius
    ASSERT_NO_THROW(s.validate(c.chart.get()));
    const sand::TinSandTool tool(c.chart, s);
    const sand::SandGrid cells(c.chart);
    const std::vector<float> flat(t.heights().begin(), t.heights().end());

    const StampOutcome ref = stampAt(t, pipe, tool, cells, c.reference, c.radius);
    ASSERT_GT(ref.displaced, 0.0);
    ASSERT_LT(ref.rings[0], 0.0) << "the imprint";
    ASSERT_GT(ref.rings[2] + ref.rings[3] + ref.rings[4], 0.0) << "the rampart";
    pipe.undo();
    ASSERT_TRUE(std::equal(flat.begin(), flat.end(), t.heights().begin()));

    const int m = c.chart->grid().m();
    std::uniform_int_distribution<int> anyU(0, m), anyV(c.vFirst, c.vLast);
    std::vector<core::GridPoint> where = c.special;
    for (int k = 0; k < 8; ++k) where.push_back({anyU(rng), anyV(rng)});
    double worstAway = 0, worstSpecial = 0, worstDrift = 0;
    for (std::size_t k = 0; k < where.size(); ++k) {
      const core::GridPoint at = where[k];
      SCOPED_TRACE("(" + std::to_string(at.u) + ", " + std::to_string(at.v) + ")");
      const StampOutcome o = stampAt(t, pipe, tool, cells, at, c.radius);
      EXPECT_LE(o.volumeDrift, 1e-9);
      EXPECT_TRUE(o.consistent) << o.why;
      EXPECT_NEAR(o.displaced / ref.displaced, 1.0, 0.05);
      // Where the grid's points fall in the rings moves up to 0.09 of the imprint from ring to
      // ring between any two interior points; a region cut at a fold or a seam moves half of it.
      const double diff = profileDifference(o, ref);
      EXPECT_LE(diff, 0.15);
      (k < c.special.size() ? worstSpecial : worstAway) =
          std::max(k < c.special.size() ? worstSpecial : worstAway, diff);
      worstDrift = std::max(worstDrift, o.volumeDrift);
      pipe.undo();
      ASSERT_TRUE(std::equal(flat.begin(), flat.end(), t.heights().begin()));
    }
    std::cout << c.name << ": profile against the reference stamp's, largest difference "
              << worstSpecial << " on folds/seams, " << worstAway << " at random points; volume "
              << "drift at most " << worstDrift << "\n";
  }
}

// A stroke that crosses a fold or a seam reuses one region TIN across it: the volume kept and the
// twins one height after every stamp.
TEST(TinSandGlued, AStrokeAcrossAFoldOrASeamReusesItsRegionTin) {
  for (const StampCase& c : stampCases()) {
    SCOPED_TRACE(c.name);
    SandScene scene(c);
    auto& [t, pipe, tool, cells] = scene;
    // Across u = 0 (the octahedral chart's fold, the tubes' u seam), four cells.
    const core::GridPoint mid = c.special[c.name == "cylinder" ? 0 : 2];
    const core::Chart& chart = *c.chart;
    const auto input = [&](int du) {
      const core::GridPoint p = chart.continued(mid.u + du, mid.v);
      return edit::ToolInput{
          chart.position(p.u, p.v, 0.0) + (kDepth - 150.0 + c.radius) * chart.up(p.u, p.v), 0.0};
    };
    double before = cells.volume(t.heights());
    pipe.beginStroke(tool, input(-2));
    for (int du = -1; du <= 2; ++du) {
      pipe.moveTo(input(du));
      const double after = cells.volume(t.heights());
      EXPECT_LE(std::abs(after - before) / cells.absVolume(t.heights()), 1e-9) << du;
      EXPECT_TRUE(edittest::consistentHeights(t)) << du;
      before = after;
    }
    pipe.endStroke();
    EXPECT_GT(tool.stamps(), 1u);
    EXPECT_EQ(tool.tinsMade(), 1u) << "one region TIN for the stroke across the fold or seam";
    EXPECT_TRUE(edittest::boundsEqualFullRebuild(t));
  }
}

// A tube's region patch (what the AR view draws in place of the 4-8 mesh) lies on the tube:
// every vertex is its TIN point's surface point (whose projection into the region's plane is
// the TIN's (x, y)) raised by its height along the normal, and the patch stands for both twins
// of a seam's points. It has no plane (the haptic path feels the grid there).
TEST(TinSandGlued, ATubesRegionPatchLiesOnTheTube) {
  for (const StampCase& c : stampCases()) {
    if (c.name == "octahedral") continue;
    SCOPED_TRACE(c.name);
    SandScene scene(c);
    auto& [t, pipe, tool, cells] = scene;
    const core::GridPoint at = c.special[c.name == "cylinder" ? 0 : 2];  // on the u seam
    (void)stampAt(t, pipe, tool, cells, at, c.radius);
    ASSERT_NE(tool.strokeTin(), nullptr);
    const sand::StrokeTin& region = *tool.strokeTin();
    const terrain::MeshPatch p = region.patch();
    EXPECT_FALSE(p.plane.has_value());
    const tin::Tin tin = region.sand().tin().toTin();
    ASSERT_EQ(p.positions.size(), tin.xy.size());
    double worstPlane = 0, worstHeight = 0;
    for (std::size_t i = 0; i < tin.xy.size(); ++i) {
      const auto uv = c.chart->inverse(p.positions[i]);
      ASSERT_TRUE(uv.has_value());
      const Eigen::Vector3d foot = c.chart->positionAt(uv->x(), uv->y(), 0.0);
      worstPlane = std::max(worstPlane, (region.frame().project(foot) - tin.xy[i]).norm());
      worstHeight = std::max(worstHeight, std::abs((p.positions[i] - foot).norm() - tin.h[i]));
    }
    EXPECT_LE(worstPlane, 1e-6 * c.radius) << "the plane point's surface point";
    EXPECT_LE(worstHeight, 1e-6 * c.radius) << "raised by the height along the normal";
    const int m = c.chart->grid().m();
    const auto replaces = [&](int u, int v) {
      return std::binary_search(p.replaces.begin(), p.replaces.end(), c.chart->grid().index(u, v));
    };
    EXPECT_TRUE(replaces(0, at.v) && replaces(m, at.v)) << "both twins of the seam's point";
  }
}

}  // namespace
