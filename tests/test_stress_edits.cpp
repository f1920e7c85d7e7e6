// Issue 9's edit stress test: random edits of every tool (brush stamps and strokes in every mode,
// sand displacement, settling by thermal erosion and both diffusion schemes, undo and redo, bad
// input) at every radius from below a cell to the whole planet, at the poles, on the seam and next
// to the poles, with extreme sigma, mu and strengths that saturate the heights. After every action
// the heights are finite, within the chart's limit, seam twins and pole rows are one point; every
// few actions the nested errors equal a full recomputation bit for bit, and the mesh of random
// views is crack-free.
//
// CI's optimised pass runs 10^4 actions on a 33^2 planet (kStressActions), its sanitizer pass a
// quarter of them (the same invariants, 4x less time under ASan); PS_STRESS_SCALE=k runs k times
// as many.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/input_error.hpp"
#include "edit/brush.hpp"
#include "edit/edit_pipeline.hpp"
#include "mesh_checks.hpp"
#include "sand/displacement.hpp"
#include "sand/settler.hpp"
#include "stress_util.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

constexpr int kStressActions = 10000;

double logUniform(std::mt19937& rng, double lo, double hi) {
  std::uniform_real_distribution<double> e(std::log(lo), std::log(hi));
  return std::exp(e(rng));
}

double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// Brush settings over the whole accepted range, with weight on the extremes.
edit::BrushSettings randomBrush(std::mt19937& rng, double R, int m, double heightLimit) {
  edit::BrushSettings s;
  s.radius = edittest::randomRadius(rng, R, m);
  if (rng() % 16 == 0) s.radius = logUniform(rng, 1e-3, 1.0);  // far below a cell
  static constexpr double kSigmas[] = {1e-6, 0.01, 0.17, 0.75, 3.0, 1e6};
  s.sigma = (rng() % 3 == 0) ? logUniform(rng, 1e-6, 1e6) : kSigmas[rng() % 6];
  static constexpr double kMus[] = {0.5000001, 1.0, 2.0, 1e6};
  s.mu = kMus[rng() % 4];
  s.mode = edit::BrushMode(rng() % 3);
  // From a millimetre to far past the limit (saturating every vertex it reaches).
  s.strength = (rng() % 8 == 0) ? 1e3 * heightLimit : logUniform(rng, 1e-3, 4.0 * heightLimit);
  s.rate = rng() % 4 == 0;
  s.target = uniform(rng, -2.0 * heightLimit, 2.0 * heightLimit);
  s.spacing = (rng() % 4 == 0) ? logUniform(rng, 0.01, 1.0) : 0.25;
  return s;
}

// A tool tip anywhere around the planet: near the surface of a hard vertex, or far out.
Eigen::Vector3d randomTip(std::mt19937& rng, const terrain::Terrain& t) {
  const core::GridPoint c = edittest::randomCentre(rng, t.grid().m());
  const double h = double(t.heights()[t.grid().index(c.u, c.v)]);
  const double k = (rng() % 5 == 0) ? logUniform(rng, 1e-6, 50.0) : uniform(rng, 0.9, 1.1);
  return t.chart().position(c.u, c.v, h) * k;
}

double randomDt(std::mt19937& rng) {
  static constexpr double kDts[] = {0.0, 1e-3, 1.0 / 30.0, 1.0, 10.0};
  return kDts[rng() % 5];
}

std::vector<float> copyHeights(const terrain::Terrain& t) {
  return {t.heights().begin(), t.heights().end()};
}

class StressRig {
 public:
  // Every tool on both sphere charts; the settler reports to the undo journal as in the live app
  // (Settler::attachUndo), so an undo takes a stroke's settling back with it.
  explicit StressRig(std::uint32_t seed, bool octahedral = false)
      : terrain_(octahedral ? testkit::bumpyOctahedralTerrain(5, seed, 8000.0)
                            : testkit::bumpyTerrain(5, seed, 8000.0)),
        pipe_(terrain_),
        rng_(seed) {
    settler_.emplace(terrain_);
    settler_->attachUndo(&pipe_);
    pipe_.setUndoEnabled(true);
  }

  terrain::Terrain& terrain() { return terrain_; }
  std::mt19937& rng() { return rng_; }

  // One random action; returns its name for failure messages.
  std::string act() {
    const unsigned kind = rng_() % 20;
    if (kind < 6) return brushStamp();
    if (kind < 10) return brushStroke();
    if (kind < 13) return displace();
    if (kind < 16) return settle();
    if (kind < 18) return undoRedo();
    return badInput();
  }

 private:
  double R() const { return terrain_.chart().sphereRadius(); }
  // Tells the settler (when there is one) what an edit changed.
  void edited(const terrain::VertexBox& region) {
    if (settler_) settler_->edited(region, settler_->material());
  }
  int m() const { return terrain_.grid().m(); }

  std::string brushStamp() {
    const auto s = randomBrush(rng_, R(), m(), terrain_.heightLimit());
    pipe_.apply(edit::GaussianBrush(s), {randomTip(rng_, terrain_), randomDt(rng_)});
    edited(pipe_.lastReport().dirty);
    return "brush stamp " + edit::toString(s.mode) + " r_d=" + std::to_string(s.radius) +
           " sigma=" + std::to_string(s.sigma) + " strength=" + std::to_string(s.strength);
  }

  std::string brushStroke() {
    const auto s = randomBrush(rng_, R(), m(), terrain_.heightLimit());
    const edit::GaussianBrush brush(s);
    pipe_.beginStroke(brush, {randomTip(rng_, terrain_), randomDt(rng_)});
    const int samples = 1 + int(rng_() % 6);
    Eigen::Vector3d p = randomTip(rng_, terrain_);
    for (int i = 0; i < samples; ++i) {
      // Small steps, teleports across the planet and standing still, mixed.
      if (rng_() % 8 == 0)
        p = randomTip(rng_, terrain_);
      else
        p += s.radius * Eigen::Vector3d(uniform(rng_, -1, 1), uniform(rng_, -1, 1), 0.0);
      if (p.norm() < 1.0) p = randomTip(rng_, terrain_);
      pipe_.moveTo({p, randomDt(rng_)});
    }
    pipe_.endStroke();
    edited(terrain::VertexBox::all(terrain_.grid()));
    return "brush stroke of " + std::to_string(samples) +
           " samples, r_d=" + std::to_string(s.radius);
  }

  std::string displace() {
    sand::DisplacementSettings ds;
    const double cell = 2.0 * std::numbers::pi * R() / m();  // the largest spacing (equator)
    ds.radius = logUniform(rng_, cell, R());
    ds.rampartWidth = uniform(rng_, 0.05, 4.0);
    ds.spacing = uniform(rng_, 0.05, 1.0);
    sand::DisplacementTool tool(terrain_.chartPtr(), ds, &*settler_);
    // The sphere's centre somewhere from deep under the surface to above it.
    const core::GridPoint c = edittest::randomCentre(rng_, m());
    const double h = double(terrain_.heights()[terrain_.grid().index(c.u, c.v)]);
    const Eigen::Vector3d up = terrain_.chart().up(c.u, c.v);
    const Eigen::Vector3d p =
        terrain_.chart().position(c.u, c.v, h) + uniform(rng_, -1.5, 1.5) * ds.radius * up;
    if (p.norm() < 1.0) return "displacement skipped (tip at the centre)";
    pipe_.apply(tool, {p, 0.0});
    const auto& st = tool.lastStats();
    // Volume removed equals volume deposited (double sums), unless the rampart saturated.
    if (terrain_.heights().size() && st.removedVolume > 0 && !saturated()) {
      EXPECT_NEAR(st.depositedVolume, st.removedVolume, 1e-9 * st.removedVolume)
          << "displacement r=" << ds.radius;
    }
    return "displacement r=" + std::to_string(ds.radius);
  }

  std::string settle() {
    sand::SettleSettings ss;
    ss.method = sand::SettleMethod(rng_() % 3);
    ss.cellBudget = std::size_t(1) << (4 + rng_() % 14);
    ss.maxStepsPerFrame = 1 + int(rng_() % 16);
    ss.diffusionDt = logUniform(rng_, 1e-3, 1e3);
    settler_->setSettings(ss);
    static const char* kMaterials[] = {"sand", "mud", "pebbles"};
    settler_->setMaterial(sand::Material::preset(kMaterials[rng_() % 3]));
    const int frames = 1 + int(rng_() % 3);
    for (int i = 0; i < frames; ++i) settler_->frame();
    return "settle " + sand::toString(ss.method) + " dt=" + std::to_string(ss.diffusionDt);
  }

  std::string undoRedo() {
    if (pipe_.journal().undoCount() == 0) return "undo with nothing to undo";
    const auto now = copyHeights(terrain_);
    pipe_.undo();
    EXPECT_TRUE(edittest::consistentHeights(terrain_)) << "after undo";
    pipe_.redo();
    // Redo right after undo is the identity, bit for bit: the stroke's undo step holds the
    // settling that followed it too.
    EXPECT_TRUE(edittest::sameBits(now, terrain_.heights())) << "undo then redo changed heights";
    if (rng_() % 2 == 0) pipe_.undo();
    edited(terrain::VertexBox::all(terrain_.grid()));
    return "undo/redo";
  }

  std::string badInput() {
    const auto before = copyHeights(terrain_);
    edit::BrushSettings s;
    s.radius = 0.1 * R();
    const double nan = std::nan("");
    Eigen::Vector3d p = randomTip(rng_, terrain_);
    double dt = 0.0;
    switch (rng_() % 5) {
      case 0:
        p.x() = nan;
        break;
      case 1:
        p = Eigen::Vector3d::Zero();
        break;
      case 2:
        dt = -1.0;
        break;
      case 3:
        s.sigma = nan;
        break;
      default:
        s.strength = std::numeric_limits<double>::infinity();
        break;
    }
    bool refused = false;
    try {
      pipe_.apply(edit::GaussianBrush(s), {p, dt});
    } catch (const core::InputError&) {
      refused = true;
    }
    EXPECT_TRUE(refused) << "bad input accepted";
    EXPECT_TRUE(edittest::sameBits(before, terrain_.heights())) << "bad input changed heights";
    return "bad input";
  }

  bool saturated() const {
    const float limit = float(terrain_.heightLimit()) * 0.999f;
    for (float h : terrain_.heights()) {
      if (std::abs(h) >= limit) return true;
    }
    return false;
  }

  terrain::Terrain terrain_;
  edit::EditPipeline pipe_;
  std::optional<sand::Settler> settler_;
  std::mt19937 rng_;
};

// A random camera: close to the surface, in orbit, or far away.
terrain::Camera randomCamera(std::mt19937& rng, double R) {
  const Eigen::Vector3d dir =
      Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
  const double k = logUniform(rng, 1.4, 50.0);
  return terrain::Camera::lookAt(k * R * dir, {0, 0, 0}, {0, 0, 1}, 640, 480, 1.0);
}

// A mesh's triangles as grid-index triples, rotated to start at the smallest index.
std::set<std::tuple<std::uint64_t, std::uint64_t, std::uint64_t>> triangleSet(
    const terrain::Mesh& mesh) {
  std::set<std::tuple<std::uint64_t, std::uint64_t, std::uint64_t>> out;
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    std::uint64_t a = mesh.gridIndex[mesh.indices[3 * k]],
                  b = mesh.gridIndex[mesh.indices[3 * k + 1]],
                  c = mesh.gridIndex[mesh.indices[3 * k + 2]];
    while (a > b || a > c) std::tie(a, b, c) = std::make_tuple(b, c, a);
    out.emplace(a, b, c);
  }
  return out;
}

}  // namespace

TEST(StressEdits, RandomActionsOfEveryToolKeepEveryInvariant) {
  const int actions = kStressActions / (testkit::underAsan() ? 4 : 1) * testkit::stressScale();
  StressRig rig(20261122);
  terrain::Tessellator tess;
  std::mt19937 viewRng(7);
  for (int i = 0; i < actions; ++i) {
    const std::string what = "action " + std::to_string(i) + ": " + rig.act();
    ASSERT_TRUE(edittest::consistentHeights(rig.terrain())) << what;
    if (i % 97 == 0) {
      ASSERT_TRUE(edittest::boundsEqualFullRebuild(rig.terrain())) << what;
    }
    if (i % 4999 == 0) {
      // The whole planet (no culling) is a closed, crack-free mesh; culling only drops
      // triangles of it, so what is left in view is crack-free too.
      terrain::TessellationSettings ts;
      ts.cull = false;
      ts.triangleBudget = 0;
      ts.distMaxPx = logUniform(viewRng, 0.5, 16.0);
      const auto cam = randomCamera(viewRng, rig.terrain().chart().sphereRadius());
      const auto whole = triangleSet(tess.tessellate(rig.terrain(), cam, ts));
      ASSERT_EQ(testkit::conformityDefect(rig.terrain(), tess.mesh()), "") << what;
      ts.cull = true;
      const auto culled = triangleSet(tess.tessellate(rig.terrain(), cam, ts));
      ASSERT_LE(culled.size(), whole.size()) << what;
      for (const auto& tri : culled)
        ASSERT_TRUE(whole.count(tri)) << what << ": culling added a triangle";
    }
    if (::testing::Test::HasFailure()) FAIL() << "stopped at " << what;
  }
  ASSERT_TRUE(edittest::boundsEqualFullRebuild(rig.terrain()));
}

// The same on the octahedral chart (its folded sides and the south pole's four corners): every
// tool there too since the sand core runs on it (issue 43; the name is from when only the brush
// did).
TEST(StressEdits, RandomBrushActionsOnTheOctahedralChartKeepEveryInvariant) {
  const int actions = kStressActions / (testkit::underAsan() ? 16 : 4) * testkit::stressScale();
  StressRig rig(20261127, true);
  terrain::Tessellator tess;
  std::mt19937 viewRng(11);
  for (int i = 0; i < actions; ++i) {
    const std::string what = "action " + std::to_string(i) + ": " + rig.act();
    ASSERT_TRUE(edittest::consistentHeights(rig.terrain())) << what;
    if (i % 97 == 0) {
      ASSERT_TRUE(edittest::boundsEqualFullRebuild(rig.terrain())) << what;
    }
    if (i % 499 == 0) {
      terrain::TessellationSettings ts;
      ts.cull = false;
      ts.triangleBudget = 0;
      ts.distMaxPx = logUniform(viewRng, 0.5, 16.0);
      const auto cam = randomCamera(viewRng, rig.terrain().chart().sphereRadius());
      tess.tessellate(rig.terrain(), cam, ts);
      ASSERT_EQ(testkit::conformityDefect(rig.terrain(), tess.mesh()), "") << what;
    }
    if (::testing::Test::HasFailure()) FAIL() << "stopped at " << what;
  }
  ASSERT_TRUE(edittest::boundsEqualFullRebuild(rig.terrain()));
}

// On the octahedral chart, brushes at every grid vertex of a 33^2 planet (every third under the
// sanitizers) with radii from a few cells to beyond the planet's diameter, each followed by the
// bounds against a full rebuild, bit for bit. (The stress test above found a brush whose dirty
// box was narrowed to the rows whose floats changed, which breaks the box's mirror images.)
TEST(StressEdits, OctahedralBrushesOfEveryRadiusAtEveryVertexKeepTheBounds) {
  auto t = testkit::bumpyOctahedralTerrain(5, 3, 8000.0);
  edit::EditPipeline pipe(t);
  const double R = t.chart().sphereRadius();
  const int m = t.grid().m(), step = testkit::underAsan() ? 3 : 1;
  for (const double radius : {0.3 * R, 1.1 * R, 2.05 * R}) {
    for (int v = 0; v <= m; v += step) {
      for (int u = 0; u <= m; u += step) {
        edit::BrushSettings s;
        s.radius = radius;
        s.sigma = 0.5;
        s.strength = 50.0;
        pipe.apply(edit::GaussianBrush(s), {t.chart().position(u, v, 0.0), 1.0});
        ASSERT_TRUE(edittest::boundsEqualFullRebuild(t))
            << "brush r_d = " << radius / R << " R at (" << u << ", " << v << ")";
      }
    }
  }
}

// A local update of the bounds over any box of one quadrant (as an edit's dirty box is,
// terrain::gluedImages covering the rest), on heights that did not change, gives the bounds a full
// build gives.
TEST(StressEdits, OctahedralLocalUpdatesOverAnyQuadrantBoxEqualAFullRebuild) {
  auto t = testkit::bumpyOctahedralTerrain(5, 4, 8000.0);
  const int m = t.grid().m(), h = m / 2, step = testkit::underAsan() ? 5 : 2;
  int boxes = 0;
  for (int qu = 0; qu < 2; ++qu)
    for (int qv = 0; qv < 2; ++qv)
      for (int u0 = qu * h; u0 <= qu * h + h; u0 += step)
        for (int u1 = u0; u1 <= qu * h + h; u1 += 3)
          for (int v0 = qv * h; v0 <= qv * h + h; v0 += step)
            for (int v1 = v0; v1 <= qv * h + h; v1 += 3) {
              t.commitEdit({u0, u1, v0, v1});
              ++boxes;
              ASSERT_TRUE(edittest::boundsEqualFullRebuild(t))
                  << "box [" << u0 << ", " << u1 << "] x [" << v0 << ", " << v1 << "]";
            }
  EXPECT_GT(boxes, testkit::underAsan() ? 400 : 2000);
}
