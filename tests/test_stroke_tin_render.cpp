// The sand TIN's region drawn by the renderer (issue 27): the view's 4-8 mesh with the region
// TIN spliced in (terrain::SplicedView) through PlanetRenderer, on headless OpenGL (skipped with
// a message where EGL is missing). What is checked is what the picture shows: the depth inside
// the region is the TIN's surface, not the grid's mesh; no background shows through the join
// from grazing views; the patch's own shading is its facets' slope; drawing is deterministic.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "edit/edit_pipeline.hpp"
#include "gl_test.hpp"
#include "mesh_checks.hpp"
#include "render/planet_renderer.hpp"
#include "render/projection.hpp"
#include "sand/tin_sand_tool.hpp"
#include "small_planet.hpp"
#include "terrain/mesh_patch.hpp"
#include "terrain/terrain.hpp"
#include "terrain/tessellator.hpp"
#include "test_edit_util.hpp"
#include "test_sand_util.hpp"
#include "test_terrains.hpp"

using namespace ps;

namespace {

using testkit::kSmallPlanetRadius;
constexpr double kLat = 15.0, kLon = 40.0;

// A 513^2 planet of 20 km radius (245 m cells) after a 2-stamp stroke of 1,200 m stamps pressed
// 300 m: the TIN's walls are a rim wide, the grid's a cell.
struct Scene {
  std::shared_ptr<const core::Chart> chart = sandtest::sphereChart(9, kSmallPlanetRadius);
  terrain::Terrain planet{chart, testkit::bumpyHeights(*chart, 3, 100.0)};
  sand::TinSandTool tool{chart, [] {
                           sand::TinSandToolSettings s;
                           s.radius = 1200.0;
                           return s;
                         }()};
  Scene() {
    edit::EditPipeline pipe(planet);
    pipe.beginStroke(tool, {edittest::latLon(kLat, kLon, kSmallPlanetRadius + 900.0, 1.0), 0.0});
    pipe.moveTo({edittest::latLon(kLat, kLon + 2.0, kSmallPlanetRadius + 900.0, 1.0), 0.0});
    pipe.endStroke();
  }
};

Scene& scene() {
  static Scene s;
  return s;
}

// A camera `dist` m from the stroke's middle, `above` m over it, from azimuth `az` (radians,
// from east toward north).
terrain::Camera cameraAt(double az, double dist, double above, int w = 320, int h = 240) {
  const Eigen::Vector3d target = edittest::latLon(kLat, kLon + 1.0, kSmallPlanetRadius, 1.0);
  const Eigen::Vector3d up = target.normalized();
  const Eigen::Vector3d east = Eigen::Vector3d::UnitZ().cross(up).normalized();
  const Eigen::Vector3d north = up.cross(east);
  const Eigen::Vector3d eye =
      target + dist * (std::cos(az) * east + std::sin(az) * north) + above * up;
  return terrain::Camera::lookAt(eye, target, up, w, h, 1.0);
}

const terrain::Mesh& tessellate(terrain::Tessellator& tess, const terrain::Camera& cam) {
  terrain::TessellationSettings ts;
  ts.distMaxPx = 2.0;
  ts.triangleBudget = 0;
  return tess.tessellate(scene().planet, cam, ts);
}

Eigen::Vector3d rayOf(const terrain::Camera& cam, double px, double py) {
  const Eigen::Vector3d c((px - cam.cx) / cam.fx, (py - cam.cy) / cam.fy, 1.0);
  return cam.rotation.transpose() * c;
}

// The triangles [from, to) of the mesh: the nearest ray parameter t (ray
// o + t d, o relative to the mesh's eye), or infinity.
double nearestHit(const terrain::Mesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                  std::size_t from = 0, std::size_t to = std::numeric_limits<std::size_t>::max()) {
  double best = std::numeric_limits<double>::infinity();
  to = std::min(to, mesh.indices.size());
  for (std::size_t t = from; t + 2 < to; t += 3)
    best = std::min(best, testkit::rayMeetsTriangle(mesh, t, o, d));
  return best;
}

// nearestHit for the rays of one camera's pixels, each tested only against the triangles whose
// projection's box (a pixel wider each way) holds its pixel: a ray through a pixel meets a
// triangle in front of the camera only within the triangle's projection, and a triangle with a
// corner at or behind the camera is tested by every ray. The same hits as testing them all.
class PixelHits {
 public:
  PixelHits(const terrain::Mesh& mesh, const terrain::Camera& cam, std::size_t from,
            std::size_t to = std::numeric_limits<std::size_t>::max())
      : mesh_(mesh),
        o_(cam.eye - mesh.eye),
        cols_((cam.width + kBin - 1) / kBin),
        rows_((cam.height + kBin - 1) / kBin),
        bins_(std::size_t(cols_) * std::size_t(rows_)) {
    to = std::min(to, mesh.indices.size());
    for (std::size_t t = from; t + 2 < to; t += 3) {
      double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
      bool front = true;
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::Vector3d c =
            cam.rotation * (mesh.positions[mesh.indices[t + k]].cast<double>() - o_);
        if (!(c.z() > 1e-9)) front = false;
        if (!front) break;
        const Eigen::Vector2d p = cam.project(c);
        x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
        y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
      }
      if (!front) {
        everywhere_.push_back(t);
        continue;
      }
      const int bx0 = std::max(0, int(std::floor((x0 - 1) / kBin)));
      const int by0 = std::max(0, int(std::floor((y0 - 1) / kBin)));
      const int bx1 = std::min(cols_ - 1, int(std::floor((x1 + 1) / kBin)));
      const int by1 = std::min(rows_ - 1, int(std::floor((y1 + 1) / kBin)));
      for (int by = by0; by <= by1; ++by)
        for (int bx = bx0; bx <= bx1; ++bx)
          bins_[std::size_t(by) * std::size_t(cols_) + std::size_t(bx)].push_back(t);
    }
  }

  // The nearest t along the ray through pixel (x, y), whose direction is d.
  double nearest(int x, int y, const Eigen::Vector3d& d) const {
    double best = std::numeric_limits<double>::infinity();
    for (const std::size_t t :
         bins_[std::size_t(y / kBin) * std::size_t(cols_) + std::size_t(x / kBin)])
      best = std::min(best, testkit::rayMeetsTriangle(mesh_, t, o_, d));
    for (const std::size_t t : everywhere_)
      best = std::min(best, testkit::rayMeetsTriangle(mesh_, t, o_, d));
    return best;
  }

 private:
  static constexpr int kBin = 16;
  const terrain::Mesh& mesh_;
  Eigen::Vector3d o_;
  int cols_, rows_;
  std::vector<std::vector<std::size_t>> bins_;
  std::vector<std::size_t> everywhere_;
};

render::RenderStyle plainStyle() {
  render::RenderStyle style;
  style.sun = Eigen::Vector3d(0.3, -0.5, 1.0).normalized();
  return style;
}

// Pixels of `image` that show the background colour exactly.
cv::Mat backgroundMask(const cv::Mat& image, const cv::Vec3b& bg) {
  cv::Mat mask;
  cv::inRange(image, cv::Scalar(bg[0], bg[1], bg[2]), cv::Scalar(bg[0], bg[1], bg[2]), mask);
  return mask;
}

}  // namespace

TEST(StrokeTinRender, InsideTheRegionTheDepthIsTheTinSurfaceNotTheGrids) {
  SKIP_WITHOUT_GL();
  Scene& s = scene();
  ASSERT_NE(s.tool.strokeTin(), nullptr);
  const auto patch = std::make_shared<const terrain::MeshPatch>(s.tool.strokeTin()->patch());
  render::EglContext ctx;
  render::PlanetRenderer renderer;
  std::size_t inside = 0, differ = 0, gridWins = 0;
  std::vector<double> offTin;  // |drawn - TIN| along the optical axis, m
  // Oblique views down onto the furrow from two sides.
  for (const double az : {0.4, 2.2}) {
    const terrain::Camera cam = cameraAt(az, 5000.0, 4000.0);
    terrain::Tessellator tess;
    const terrain::Mesh& grid = tessellate(tess, cam);
    terrain::SplicedView spliced;
    const terrain::Mesh& mesh = spliced.view(grid, patch, *s.chart);
    ASSERT_GT(spliced.report().dropped, 50u);
    renderer.renderAR({}, s.planet, mesh, cam, plainStyle());
    const cv::Mat depth = renderer.readDepth();
    ASSERT_EQ(depth.type(), CV_32F);
    const render::DepthRange range = render::depthRangeFor(cam, s.planet);
    const Eigen::Matrix4d P = render::clipFromCamera(cam, range.nearZ, range.farZ);
    const auto& region = *s.tool.strokeTin();
    const double cell = M_PI * kSmallPlanetRadius / s.chart->grid().m();
    const Eigen::Vector3d o = cam.eye - mesh.eye;
    const PixelHits tinHits(mesh, cam, mesh.patchIndexBegin), gridHits(grid, cam, 0);
    for (int y = 0; y < cam.height; y += 3) {
      for (int x = 0; x < cam.width; x += 3) {
        const Eigen::Vector3d d = rayOf(cam, x, y);
        const double tTin = tinHits.nearest(x, y, d);
        if ((x + y) % 87 == 0) {  // now and then, every triangle: the bins lose no hit
          ASSERT_EQ(tTin, nearestHit(mesh, o, d, mesh.patchIndexBegin)) << x << ", " << y;
        }
        if (!std::isfinite(tTin)) continue;
        // Well inside the TIN's domain (four cells in from its border: past the overlap ring,
        // where the view's kept triangles may lie nearer).
        const Eigen::Vector3d hit = mesh.eye + o + tTin * d;
        if (region.sand().tin().depthInside(
                region.frame().project(hit.normalized() * kSmallPlanetRadius)) < 4 * cell)
          continue;
        const double tGrid = gridHits.nearest(x, y, d);
        ASSERT_TRUE(std::isfinite(tGrid));
        // Depth along the optical axis (camera z) from the window depth.
        const double ndc = 2.0 * depth.at<float>(y, x) - 1.0;
        const double zDrawn = P(2, 3) / (ndc - P(2, 2));
        const double zOf = d.dot(cam.rotation.row(2).transpose());  // camera z per unit t
        const double zTin = tTin * zOf, zGrid = tGrid * zOf;
        ++inside;
        offTin.push_back(std::abs(zDrawn - zTin));
        if (std::abs(zTin - zGrid) > 5.0) {
          ++differ;
          gridWins += std::abs(zDrawn - zGrid) < std::abs(zDrawn - zTin);
        }
      }
    }
  }
  std::sort(offTin.begin(), offTin.end());
  const auto at = [&](double q) { return offTin[std::size_t(q * double(offTin.size() - 1))]; };
  std::cout << inside << " pixels inside the region: drawn depth off the TIN's surface by "
            << at(0.5) << " m (median), " << at(0.99) << " m (99th percentile), " << at(1.0)
            << " m (largest: a pixel centre beside an edge that hides what is behind it); at "
            << differ << " of them the grid's mesh lies more than 5 m off the TIN, and at "
            << gridWins << " of those the grid's is drawn (a kept triangle reaching in front)\n";
  ASSERT_GT(inside, 500u);
  EXPECT_GT(differ, 50u) << "the views must tell the TIN from the grid";
  EXPECT_LT(at(0.5), 0.1);
  EXPECT_LT(at(0.99), 0.1);
  EXPECT_LT(double(gridWins), 0.01 * double(differ));
}

// With no exaggeration the patch's per-pixel normal (from its height's gradient across each
// facet, mesh_shaders.hpp) is the facet's own normal: per-pixel and faceted pictures of the
// patch agree. A wrong gradient (a sign, the 1 / (1 - g.up) factor, the grid's tiles read
// instead) shows as a difference on the furrow's walls.
TEST(StrokeTinRender, ThePatchsPerPixelLightIsItsFacetsSlope) {
  SKIP_WITHOUT_GL();
  Scene& s = scene();
  const auto patch = std::make_shared<const terrain::MeshPatch>(s.tool.strokeTin()->patch());
  render::EglContext ctx;
  render::PlanetRenderer renderer;
  const terrain::Camera cam = cameraAt(0.4, 4000.0, 5000.0);
  terrain::Tessellator tess;
  terrain::SplicedView spliced;
  const terrain::Mesh& mesh = spliced.view(tessellate(tess, cam), patch, *s.chart);
  render::RenderStyle style = plainStyle();
  style.reliefScale = 1;
  const cv::Mat perPixel = renderer.renderAR({}, s.planet, mesh, cam, style);
  style.shading = render::Shading::kFaceted;
  const cv::Mat faceted = renderer.renderAR({}, s.planet, mesh, cam, style);
  // The pixels whose nearest surface is a patch triangle well inside the region.
  const auto& region = *s.tool.strokeTin();
  const double cell = M_PI * kSmallPlanetRadius / s.chart->grid().m();
  const Eigen::Vector3d o = cam.eye - mesh.eye;
  const PixelHits patchHits(mesh, cam, mesh.patchIndexBegin),
      keptHits(mesh, cam, 0, mesh.patchIndexBegin);
  double sum = 0, worst = 0;
  std::size_t n = 0;
  for (int y = 1; y < cam.height - 1; y += 2) {
    for (int x = 1; x < cam.width - 1; x += 2) {
      const Eigen::Vector3d d = rayOf(cam, x, y);
      const double t = patchHits.nearest(x, y, d);
      if (!std::isfinite(t) || keptHits.nearest(x, y, d) < t) continue;
      const Eigen::Vector3d hit = mesh.eye + o + t * d;
      if (region.sand().tin().depthInside(
              region.frame().project(hit.normalized() * kSmallPlanetRadius)) < 4 * cell)
        continue;
      const cv::Vec3b a = perPixel.at<cv::Vec3b>(y, x), b = faceted.at<cv::Vec3b>(y, x);
      double diff = 0;
      for (int k = 0; k < 3; ++k) diff = std::max(diff, std::abs(double(a[k]) - double(b[k])));
      sum += diff;
      worst = std::max(worst, diff);
      ++n;
    }
  }
  std::cout << n << " patch pixels: per pixel (relief x1) against facets, mean " << sum / n
            << " grey levels, largest " << worst << "\n";
  ASSERT_GT(n, 500u);
  EXPECT_LT(sum / double(n), 1.5);
}

// Whether the ray from the eye through pixel (x, y) passes under the TIN's surface (more than
// `slack` m below it) somewhere over the TIN's domain: the full-resolution surface there, by
// brute force (every 2 m along the ray within 20 km). Such a ray must meet the surface; one
// drawn as background leaked through the join. A ray that stays above it (past the
// silhouette, where the TIN lies lower than the grid's mesh did) shows the background rightly.
double depthUnderTheTin(const terrain::Camera& cam, int x, int y) {
  const auto& region = *scene().tool.strokeTin();
  const Eigen::Vector3d d = rayOf(cam, x, y).normalized();
  double deepest = 0;
  for (double t = 0; t < 20e3; t += 2.0) {
    const Eigen::Vector3d p = cam.eye + t * d;
    const Eigen::Vector2d xy = region.frame().project(p.normalized() * kSmallPlanetRadius);
    const double h = region.sand().tin().heightAt(xy);
    if (!std::isnan(h)) deepest = std::max(deepest, h - (p.norm() - kSmallPlanetRadius));
  }
  return deepest;
}

// Grazing views of the join through the renderer itself: a pixel drawn as background whose ray
// passes under the TIN's surface is a leak. Measured for the patch with and without its
// overlap ring, with and without skirts; the default (the ring, no skirts) must leak nothing.
// PS_TIN_VIEW_PICTURES=DIR writes one view of each.
TEST(StrokeTinRender, NoBackgroundLeaksThroughTheJoinInTheRenderedPicture) {
  SKIP_WITHOUT_GL();
  Scene& s = scene();
  struct Join {
    const char* name;
    double marginCells;
    terrain::PatchJoin join;
    std::size_t leaks = 0, silhouette = 0;
  };
  Join joins[] = {{"no overlap", 0.0, terrain::PatchJoin::kNone},
                  {"no overlap + 20 m skirts", 0.0, terrain::PatchJoin::kSkirts},
                  {"2-cell overlap", 2.0, terrain::PatchJoin::kNone},
                  {"2-cell overlap + 20 m skirts", 2.0, terrain::PatchJoin::kSkirts}};
  render::EglContext ctx;
  render::PlanetRenderer renderer;
  const cv::Vec3b magenta(255, 0, 255);
  const cv::Mat bg(240, 320, CV_8UC3, cv::Scalar(magenta[0], magenta[1], magenta[2]));
  const char* dir = std::getenv("PS_TIN_VIEW_PICTURES");
  std::size_t planetPixels = 0;
  // The patch is drawn as flat triangles, chords under the TIN's surface taken onto the sphere
  // by up to L^2 / 8R on an edge of length L (the grid's mesh sags alike): a ray that grazes the
  // silhouette between chord and surface is no leak. A ray through a hole in the join goes
  // under the surface by far more (kilometres, in the views without the overlap).
  double slack = 0.5;
  {
    const terrain::MeshPatch p = s.tool.strokeTin()->patch();
    for (std::size_t t = 0; t < p.indices.size(); ++t) {
      const std::size_t next = t % 3 == 2 ? t - 2 : t + 1;
      const double L = (p.positions[p.indices[t]] - p.positions[p.indices[next]]).norm();
      slack = std::max(slack, 0.5 + L * L / (8 * kSmallPlanetRadius));
    }
  }
  // From four sides, 9 km away: 3 km up (the region in front of the horizon), 1.5 km and
  // 0.6 km (grazing: the region on the horizon).
  for (int view = 0; view < 12; ++view) {
    const double above = view < 4 ? 3000.0 : view < 8 ? 1500.0 : 600.0;
    const terrain::Camera cam = cameraAt(M_PI / 2 * (view % 4) + 0.3, 9000.0, above);
    terrain::Tessellator tess;
    const terrain::Mesh& grid = tessellate(tess, cam);
    const cv::Mat plain = renderer.renderAR(bg, s.planet, grid, cam, plainStyle());
    const cv::Mat plainBg = backgroundMask(plain, magenta);
    planetPixels += std::size_t(plain.total()) - std::size_t(cv::countNonZero(plainBg));
    for (Join& j : joins) {
      const auto patch =
          std::make_shared<const terrain::MeshPatch>(s.tool.strokeTin()->patch(j.marginCells));
      terrain::SplicedView spliced;
      const terrain::Mesh& mesh = spliced.view(grid, patch, *s.chart, j.join, 20.0);
      const cv::Mat img = renderer.renderAR(bg, s.planet, mesh, cam, plainStyle());
      const cv::Mat imgBg = backgroundMask(img, magenta);
      for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x) {
          // Where the grid's view showed the background too, its ray missed the grid's mesh,
          // which lies within the region's tolerance of the TIN.
          if (!imgBg.at<std::uint8_t>(y, x) || plainBg.at<std::uint8_t>(y, x)) continue;
          if (depthUnderTheTin(cam, x, y) > slack)
            ++j.leaks;
          else
            ++j.silhouette;
        }
      if (dir && view == 1)
        cv::imwrite((std::filesystem::path(dir) /
                     ("join_" + std::to_string(int(j.marginCells)) +
                      (j.join == terrain::PatchJoin::kSkirts ? "_skirts" : "") + ".png"))
                        .string(),
                    img);
    }
    if (dir && view == 1) {
      cv::imwrite((std::filesystem::path(dir) / "join_grid.png").string(), plain);
      // The grid's view | the spliced one (docs/images/stroke_tin_view.png).
      const auto patch = std::make_shared<const terrain::MeshPatch>(s.tool.strokeTin()->patch());
      terrain::SplicedView spliced;
      cv::Mat both;
      cv::hconcat(
          plain,
          renderer.renderAR(bg, s.planet, spliced.view(grid, patch, *s.chart), cam, plainStyle()),
          both);
      cv::imwrite((std::filesystem::path(dir) / "grid_and_spliced.png").string(), both);
    }
  }
  std::cout << "a leak: a background pixel whose ray passes more than " << slack
            << " m under the TIN's surface\n";
  for (const Join& j : joins)
    std::cout << j.name << ": " << j.leaks << " background pixels whose ray passes under the TIN; "
              << j.silhouette << " more than the grid's view past the silhouette (12 views, "
              << planetPixels << " planet pixels)\n";
  EXPECT_GT(planetPixels, 100000u);
  EXPECT_GT(joins[0].leaks, 0u) << "these views find the holes of a patch without its ring";
  EXPECT_EQ(joins[2].leaks, 0u) << "the overlap ring closes the join in the picture";
  EXPECT_EQ(joins[3].leaks, 0u);
}

// The same scene drawn by two renderers, and by one twice after drawing another view between:
// bit-identical pictures (replays write the same frames every time).
TEST(StrokeTinRender, TheSplicedViewDrawsTheSamePictureEveryTime) {
  SKIP_WITHOUT_GL();
  Scene& s = scene();
  render::EglContext ctx;
  const terrain::Camera cam = cameraAt(1.0, 6000.0, 3000.0);
  const terrain::Camera other = cameraAt(3.0, 9000.0, 1500.0);
  terrain::Tessellator tess;
  terrain::SplicedView spliced;
  const auto patch = std::make_shared<const terrain::MeshPatch>(s.tool.strokeTin()->patch());
  render::PlanetRenderer a;
  const cv::Mat first = a.renderAR(
      {}, s.planet, spliced.view(tessellate(tess, cam), patch, *s.chart), cam, plainStyle());
  const std::uint64_t generation = spliced.view(tessellate(tess, cam), patch, *s.chart).generation;
  EXPECT_EQ(generation, spliced.view(tessellate(tess, cam), patch, *s.chart).generation)
      << "an unchanged view and patch are not spliced again";
  terrain::Tessellator tess2;
  terrain::SplicedView spliced2;
  a.renderAR({}, s.planet, spliced2.view(tessellate(tess2, other), patch, *s.chart), other,
             plainStyle());
  const cv::Mat again = a.renderAR(
      {}, s.planet, spliced.view(tessellate(tess, cam), patch, *s.chart), cam, plainStyle());
  render::PlanetRenderer b;
  terrain::Tessellator tess3;
  terrain::SplicedView spliced3;
  const auto patch2 = std::make_shared<const terrain::MeshPatch>(s.tool.strokeTin()->patch());
  const cv::Mat fresh = b.renderAR(
      {}, s.planet, spliced3.view(tessellate(tess3, cam), patch2, *s.chart), cam, plainStyle());
  EXPECT_EQ(cv::norm(first, again, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(first, fresh, cv::NORM_INF), 0.0);
  // And the patch is drawn: the picture differs from the grid's alone.
  const cv::Mat gridOnly = b.renderAR({}, s.planet, tessellate(tess3, cam), cam, plainStyle());
  EXPECT_GT(cv::norm(first, gridOnly, cv::NORM_L1), 0.0);
}
