// `export --tin` (io/tin_export, io::exportTinFromFile): the files as written, read back and
// measured here against every sample by brute force; web DEM tile encodings; refusals.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "app/build_paths.hpp"
#include "core/cylinder_chart.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/torus_chart.hpp"
#include "fresh_dir.hpp"
#include "io/export.hpp"
#include "io/height_image.hpp"
#include "io/heightmap_import.hpp"
#include "io/planet_file.hpp"
#include "io/tin_export.hpp"
#include "stress_util.hpp"
#include "test_terrains.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_mesher.hpp"
#include "tin/triangle_error.hpp"

using namespace ps;
namespace fs = std::filesystem;

namespace {

struct ObjMesh {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<std::uint32_t, 3>> f;
};

ObjMesh readObjTriangles(const fs::path& p) {
  std::ifstream in(p);
  ObjMesh m;
  std::string tag;
  while (in >> tag) {
    if (tag == "v") {
      double x, y, z;
      in >> x >> y >> z;
      m.v.emplace_back(x, y, z);
    } else if (tag == "f") {
      std::array<std::uint32_t, 3> t;
      in >> t[0] >> t[1] >> t[2];
      m.f.push_back({t[0] - 1, t[1] - 1, t[2] - 1});
    } else {
      std::getline(in, tag);
    }
  }
  return m;
}

// Brute force: the distance from p to the nearest triangle of the mesh.
double distanceToMesh(const Eigen::Vector3d& p, const ObjMesh& m) {
  double best = INFINITY;
  for (const auto& f : m.f)
    best = std::min(best, tin::pointTriangleDistance(p, m.v[f[0]], m.v[f[1]], m.v[f[2]]));
  return best;
}

// The TIN's edges along the rows v = 0 and v = last (a cylinder's open ends).
std::size_t endEdgesOf(const tin::Tin& tin, double last) {
  std::size_t n = 0;
  for (const auto& tri : tin.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto& a = tin.xy[tri[std::size_t(k)]];
      const auto& b = tin.xy[tri[std::size_t((k + 1) % 3)]];
      if ((a.y() == 0 && b.y() == 0) || (a.y() == last && b.y() == last)) ++n;
    }
  return n;
}

// The smallest angle (degrees) of the TIN's triangles in the lattice (the plane the quality
// mode refines in), computed from their corners' (x, y).
double smallestLatticeAngleDeg(const tin::Tin& tin) {
  double smallest = 180;
  for (const auto& tri : tin.triangles)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d& a = tin.xy[tri[std::size_t(k)]];
      const Eigen::Vector2d e1 = tin.xy[tri[std::size_t((k + 1) % 3)]] - a;
      const Eigen::Vector2d e2 = tin.xy[tri[std::size_t((k + 2) % 3)]] - a;
      const double c = e1.dot(e2) / (e1.norm() * e2.norm());
      smallest = std::min(smallest, std::acos(std::clamp(c, -1.0, 1.0)) * 180 / M_PI);
    }
  return smallest;
}

// A 16-bit grey PNG of random relief (row 0 north), values = metres * 10 (scale 0.1).
fs::path writeRelief(const fs::path& dir, int w, int h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0, 1);
  cv::Mat img(h, w, CV_16UC1);
  const double cx = w * uni(rng), cy = h * uni(rng);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double z = 300 * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / 150.0) +
                       40 * std::sin(0.4 * x) * std::cos(0.3 * y) + 5 * uni(rng) + 100;
      img.at<std::uint16_t>(y, x) = std::uint16_t(std::lround(z * 10));
    }
  const fs::path p = dir / "relief.png";
  cv::imwrite(p.string(), img);
  return p;
}

io::ImportOptions heightmapOptions(double spacing) {
  io::ImportOptions o;
  o.chart = io::ChartKind::kFlat;
  o.scale = 0.1;
  o.offset = 0.0;
  o.spacing = spacing;
  return o;
}

// The exported mesh m of planet t: closed (no border, manifold, no degenerate triangle, Euler 2),
// facing outwards, every height sample within maxError of it.
void expectClosedOutwardSphere(const ObjMesh& m, const terrain::Terrain& t, double maxError,
                               const std::string& what) {
  const tin::MeshTopology top = tin::meshTopology(m.v.size(), m.f);
  EXPECT_EQ(top.borderEdges, 0u) << what;
  EXPECT_EQ(top.nonManifoldEdges, 0u) << what;
  EXPECT_EQ(top.degenerate, 0u) << what;
  EXPECT_EQ(top.euler(), 2) << what;
  double volume6 = 0;
  for (const auto& f : m.f) volume6 += m.v[f[0]].dot(m.v[f[1]].cross(m.v[f[2]]));
  EXPECT_GT(volume6, 0) << "triangles face outwards " << what;
  double worst = 0;
  const int side = t.grid().side();
  for (int v = 0; v < side; ++v)
    for (int u = 0; u < side; ++u)
      worst = std::max(worst, distanceToMesh(t.chart().position(u, v, t.height(u, v)), m));
  EXPECT_LE(worst, maxError) << what;
}

// The charts with glued sides on 2^n + 1 squared heights, each with the Euler characteristic of
// its closed (or, for the cylinder, open-ended) surface.
struct GluedSurface {
  std::shared_ptr<const core::Chart> chart;
  int euler;
  bool openEnds;
};

std::vector<GluedSurface> gluedSurfaces(int n) {
  const core::GridSize g(n);
  return {{testkit::octahedralChart(n), 2, false},
          {testkit::octahedralChart(n, core::OctahedralChart::Mapping::kCentral), 2, false},
          {std::make_shared<core::TorusChart>(g, 4.0e6, 1.5e6), 0, false},
          {std::make_shared<core::CylinderChart>(g, 2.0e6, 8.0e6), 0, true}};
}

TEST(TinExport, AHeightmapIsMeshedOnItsOwnSamplesWithinTheErrorAsWritten) {
  const fs::path dir = testkit::freshDir("tin_heightmap");
  const int w = 37, h = 29;
  const double spacing = 2.5, maxError = 1.5;
  const fs::path png = writeRelief(dir, w, h, 3);
  std::vector<std::string> notes;
  io::TinExportOptions o;
  o.maxErrorM = maxError;
  const nlohmann::json s = io::exportTinFromFile(png, heightmapOptions(spacing), dir / "t.obj",
                                                 io::ExportFormat::kObj, o, notes);
  EXPECT_LE(s["measured_error_m"].get<double>(), maxError);
  EXPECT_EQ(s["samples_checked"].get<std::size_t>(), std::size_t(w * h));
  const ObjMesh m = readObjTriangles(dir / "t.obj");
  EXPECT_EQ(m.v.size(), s["vertices"].get<std::size_t>());
  EXPECT_LT(m.v.size(), std::size_t(w * h));
  // Every vertex sits on one of the image's own samples (no resampling).
  for (const auto& p : m.v) {
    EXPECT_NEAR(p.x() / spacing, std::round(p.x() / spacing), 1e-4);
    EXPECT_NEAR(p.y() / spacing, std::round(p.y() / spacing), 1e-4);
  }
  // Brute force: every sample's height against the triangle above it in the file.
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
  double worst = 0;
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const Eigen::Vector2d p(col * spacing, (h - 1 - row) * spacing);
      const double truth = 0.1 * img.at<std::uint16_t>(row, col);
      double best = INFINITY;
      for (const auto& t : m.f) {
        const Eigen::Vector3d &a = m.v[t[0]], &b = m.v[t[1]], &c = m.v[t[2]];
        const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
        ASSERT_GT(area, 0) << "counter-clockwise seen from +z";
        const double l0 =
            ((b.x() - p.x()) * (c.y() - p.y()) - (b.y() - p.y()) * (c.x() - p.x())) / area;
        const double l1 =
            ((c.x() - p.x()) * (a.y() - p.y()) - (c.y() - p.y()) * (a.x() - p.x())) / area;
        const double l2 = 1 - l0 - l1;
        if (l0 < -1e-6 || l1 < -1e-6 || l2 < -1e-6) continue;
        best = std::min(best, std::abs(truth - (l0 * a.z() + l1 * b.z() + l2 * c.z())));
      }
      ASSERT_TRUE(std::isfinite(best))
          << "sample (" << col << ", " << row << ") is under no triangle";
      worst = std::max(worst, best);
    }
  EXPECT_LE(worst, maxError + 1e-9);
  EXPECT_GT(worst, 0.5 * maxError) << "the mesh is not finer than it needs to be";
}

TEST(TinExport, APlanetTinIsAClosedOutwardSphereWithinTheErrorOfEverySample) {
  const fs::path dir = testkit::freshDir("tin_planet");
  const terrain::Terrain t = testkit::bumpyTerrain(5, 9, 30000.0);
  io::savePlanet(t, dir / "p.planet");
  std::vector<std::string> notes;
  io::TinExportOptions o;
  o.maxErrorM = 5000.0;
  const nlohmann::json s = io::exportTinFromFile(dir / "p.planet", io::ImportOptions{},
                                                 dir / "p.obj", io::ExportFormat::kObj, o, notes);
  EXPECT_EQ(s["error_metric"], "3d");
  expectClosedOutwardSphere(readObjTriangles(dir / "p.obj"), t, o.maxErrorM, "");
}

// Every chart's planet TIN is welded by the chart's topology (issue 28): a side vertex goes in
// with its twins, and the weld joins the chart's canonical vertices. The octahedral chart's
// folded sides and corners close into a sphere (Euler 2), the torus's two seams into a torus
// (Euler 0), the cylinder's seam into a tube whose two ends are its only border (Euler 0);
// every sample within the error, as exported. The quality TIN (a minimum angle) likewise.
TEST(TinExport, EveryChartsPlanetTinIsWeldedByItsTopology) {
  const fs::path dir = testkit::freshDir("tin_charts");
  for (const GluedSurface& c : gluedSurfaces(5)) {
    const terrain::Terrain t(c.chart, testkit::bumpyHeights(*c.chart, 3, 30000.0));
    const std::string name = c.chart->name();
    io::savePlanet(t, dir / (name + ".planet"));
    std::vector<std::string> notes;
    io::TinExportOptions o;
    o.maxErrorM = 5000.0;
    const nlohmann::json s =
        io::exportTinFromFile(dir / (name + ".planet"), io::ImportOptions{}, dir / (name + ".obj"),
                              io::ExportFormat::kObj, o, notes);
    EXPECT_LE(s["measured_error_m"].get<double>(), o.maxErrorM) << name;
    const ObjMesh m = readObjTriangles(dir / (name + ".obj"));
    const tin::MeshTopology top = tin::meshTopology(m.v.size(), m.f);
    EXPECT_EQ(top.nonManifoldEdges, 0u) << name;
    EXPECT_EQ(top.degenerate, 0u) << name;
    EXPECT_EQ(top.euler(), c.euler) << name;
    // The border: none, or the cylinder's ends (the TIN's edges along the rows v = 0 and m).
    const tin::SampleField field = io::terrainSampleField(t);
    tin::SampleField tolerant = field;
    tolerant.uniformTolerance = 4000.0;
    const tin::Tin tin = tin::buildTin(tolerant, {});
    const tin::WeldedMesh welded = tin::weldTin(tolerant, tin);
    const tin::MeshTopology weldedTop = tin::meshTopology(welded.vertices, welded.triangles);
    const double last = t.grid().m();
    const std::size_t endEdges = endEdgesOf(tin, last);
    EXPECT_EQ(weldedTop.borderEdges, c.openEnds ? endEdges : 0u) << name;
    if (c.openEnds) {
      EXPECT_GT(endEdges, 0u);
      EXPECT_GT(top.borderEdges, 0u);
    } else {
      EXPECT_EQ(top.borderEdges, 0u) << name;
    }
    EXPECT_EQ(weldedTop.euler(), c.euler) << name;
  }
}

// At an octahedral fold's cone point (a grid side's midpoint) the side's two halves weld into one
// line: a TIN triangle from the cone point to a vertex on one half and one across the square, with
// its mirror image through the other half, welded into a flap, two triangles on the same three
// vertices facing apart (a 1025^2 Mars at 50 m: Euler 3, one edge of four triangles, until
// 2026-12-08). The cone point is joined to its two diagonal neighbours inward: every planet's
// welded TIN closes, and no triangle at a cone point has corners on both lines.
TEST(TinExport, AnOctahedralConePointWeldsIntoNoFlap) {
  std::vector<terrain::Terrain> planets;
  for (const int n : {6, 7})
    for (const double amplitude : {0.0, 2000.0, 20000.0})
      planets.push_back(
          amplitude == 0
              ? terrain::Terrain(testkit::octahedralChart(n),
                                 std::vector<float>(std::size_t(((1 << n) + 1) * ((1 << n) + 1))))
              : testkit::bumpyOctahedralTerrain(n, 5, amplitude));
  const fs::path mars = ps::app::sharedDir() / "data/dem/mars_mola_1440x720_u16.png";
  if (fs::exists(mars) && !testkit::underAsan()) {
    io::ImportOptions o;
    o.chart = io::ChartKind::kOctahedral;
    o.radius = 3389500.0;
    o.offset = -32768.0;
    o.westLongitudeDeg = 0.0;
    o.gridSide = 1025;
    io::ImportResult r = io::importHeightmap(mars, o);
    planets.emplace_back(r.planet.chart, std::move(r.planet.heights));
  } else {
    std::cerr << "TinExport.AnOctahedralConePointWeldsIntoNoFlap: the 1025^2 Mars is skipped ("
              << (testkit::underAsan() ? "sanitizers" : mars.string() + " is absent") << ")\n";
  }
  for (const terrain::Terrain& t : planets) {
    const double m = t.grid().m();
    for (const double error : {50.0, 500.0, 5000.0}) {
      tin::SampleField field = io::terrainSampleField(t);
      field.uniformTolerance = error;
      const tin::Tin tin = tin::buildTin(field, {});
      const tin::WeldedMesh welded = tin::weldTin(field, tin);
      const tin::MeshTopology top = tin::meshTopology(welded.vertices, welded.triangles);
      SCOPED_TRACE(t.grid().label() + " at " + std::to_string(error) + " m");
      EXPECT_EQ(top.euler(), 2);
      EXPECT_EQ(top.nonManifoldEdges, 0u);
      EXPECT_EQ(top.borderEdges, 0u);
      const std::array<Eigen::Vector2d, 4> cones{{{m / 2, 0}, {m, m / 2}, {m / 2, m}, {0, m / 2}}};
      for (const auto& tri : tin.triangles)
        for (const Eigen::Vector2d& c : cones) {
          const auto at =
              std::find_if(tri.begin(), tri.end(), [&](std::uint32_t v) { return tin.xy[v] == c; });
          if (at == tri.end()) continue;
          // No corner on the side (beyond the cone point) with another on the line from it
          // straight into the square: with its mirror image such a triangle welds into a flap.
          const Eigen::Vector2d inward = (Eigen::Vector2d(m / 2, m / 2) - c).normalized();
          const Eigen::Vector2d along(-inward.y(), inward.x());
          bool onSide = false, onLine = false;
          for (const std::uint32_t v : tri) {
            const Eigen::Vector2d d = tin.xy[v] - c;
            onSide = onSide || (d.dot(inward) == 0 && d.dot(along) != 0);
            onLine = onLine || (d.dot(along) == 0 && d.dot(inward) > 0);
          }
          EXPECT_FALSE(onSide && onLine) << "a triangle at the cone point " << c.transpose();
        }
    }
  }
}

// The quality mode (a minimum angle) on every chart (issue 43): its Steiner points on a glued
// side (the octahedral chart's folds, the torus's seams, the cylinder's seam) go in with their
// twins, so the welded mesh closes as the fewest-triangles one does; the angle holds in the
// lattice and every sample is within the error.
TEST(TinExport, EveryChartsQualityTinKeepsItsAngleAndCloses) {
  for (const GluedSurface& c : gluedSurfaces(7)) {
    const terrain::Terrain t(c.chart, testkit::bumpyHeights(*c.chart, 3, 30000.0));
    const std::string name = c.chart->name();
    const double last = t.grid().m();
    tin::SampleField field = io::terrainSampleField(t);
    field.uniformTolerance = 8000.0;
    tin::TinOptions quality;
    quality.minAngleDeg = 30;
    tin::TinReport rep;
    const tin::Tin q = tin::buildTin(field, quality, &rep);
    EXPECT_TRUE(rep.angleMet) << name << ": " << rep.smallestAngleDeg;
    EXPECT_GE(smallestLatticeAngleDeg(q), 30.0 - 1e-6) << name;
    // Steiner points on the glued sides, between grid points: the twins' path was taken.
    std::size_t onSides = 0;
    for (const auto& p : q.xy)
      if ((p.x() == 0 || p.x() == last || p.y() == 0 || p.y() == last) &&
          (p.x() != std::floor(p.x()) || p.y() != std::floor(p.y())))
        ++onSides;
    EXPECT_GT(onSides, 0u) << name;
    std::cout << name << ": quality TIN at 30 degrees, " << rep.steinerVertices
              << " Steiner vertices (greedy " << rep.greedyVertices << "), " << onSides
              << " between grid points on the sides\n";
    const tin::WeldedMesh qw = tin::weldTin(field, q);
    const tin::MeshTopology qt = tin::meshTopology(qw.vertices, qw.triangles);
    EXPECT_EQ(qt.nonManifoldEdges, 0u) << name;
    EXPECT_EQ(qt.degenerate, 0u) << name;
    EXPECT_EQ(qt.borderEdges, c.openEnds ? endEdgesOf(q, last) : 0u) << name;
    EXPECT_EQ(qt.euler(), c.euler) << name;
    const tin::TinErrorCheck qe = tin::measureTinError(field, q);
    EXPECT_EQ(qe.uncovered, 0u) << name;
    EXPECT_LE(qe.maxRatio, 1.0) << name;
  }
}

// `export --tin --min-angle` of an octahedral planet: the written OBJ is a closed outward sphere
// (Euler 2, no border, no non-manifold edge) whose triangles keep the angle in the lattice, with
// every grid vertex within the error of the written mesh (brute force).
TEST(TinExport, AQualityTinOfAnOctahedralPlanetIsClosedAndKeepsItsAngle) {
  const fs::path dir = testkit::freshDir("tin_quality_octahedral");
  const terrain::Terrain t(testkit::octahedralChart(5),
                           testkit::bumpyHeights(*testkit::octahedralChart(5), 7, 30000.0));
  io::savePlanet(t, dir / "p.planet");
  for (const double angle : {20.0, 28.0}) {
    io::TinExportOptions o;
    o.maxErrorM = 4000.0;
    o.minAngleDeg = angle;
    std::vector<std::string> notes;
    const nlohmann::json s = io::exportTinFromFile(dir / "p.planet", io::ImportOptions{},
                                                   dir / "q.obj", io::ExportFormat::kObj, o, notes);
    EXPECT_LE(s["measured_error_ratio"].get<double>(), 1.0) << angle;
    EXPECT_TRUE(s["angle_met"].get<bool>()) << angle;
    EXPECT_GE(s["smallest_angle_deg"].get<double>(), angle - 1e-6);
    expectClosedOutwardSphere(readObjTriangles(dir / "q.obj"), t, o.maxErrorM,
                              "angle " + std::to_string(angle));
  }
}

TEST(TinExport, APlanetRegionIsMeshedAloneWithinItsError) {
  const fs::path dir = testkit::freshDir("tin_region");
  const terrain::Terrain t = testkit::bumpyTerrain(6, 4, 30000.0);
  io::savePlanet(t, dir / "p.planet");
  io::TinExportOptions o;
  o.maxErrorM = 1500.0;
  o.regionDeg = std::array<double, 4>{-20.0, 30.0, 25.0, 100.0};
  std::vector<std::string> notes;
  const nlohmann::json s = io::exportTinFromFile(dir / "p.planet", io::ImportOptions{},
                                                 dir / "r.obj", io::ExportFormat::kObj, o, notes);
  EXPECT_LE(s["measured_error_ratio"].get<double>(), 1.0);
  const ObjMesh m = readObjTriangles(dir / "r.obj");
  const tin::MeshTopology top = tin::meshTopology(m.v.size(), m.f);
  EXPECT_EQ(top.euler(), 1) << "a patch of the sphere";
  EXPECT_GT(top.borderEdges, 0u);
  EXPECT_EQ(top.nonManifoldEdges, 0u);
  // Every vertex inside the region (widened to the grid's cells: 360 / 64 = 5.6 degrees).
  for (const auto& p : m.v) {
    const double lat = std::asin(p.z() / p.norm()) * 180 / M_PI;
    const double lon = std::atan2(p.y(), p.x()) * 180 / M_PI;
    EXPECT_GE(lat, -20.0 - 2.9);
    EXPECT_LE(lat, 25.0 + 2.9);
    EXPECT_GE(lon, 30.0 - 5.7);
    EXPECT_LE(lon, 100.0 + 5.7);
  }
  // Every grid vertex inside the region is within the error of the patch (brute force).
  double worst = 0;
  const int side = t.grid().side();
  for (int v = 0; v < side; ++v)
    for (int u = 0; u < side; ++u) {
      const double lat = -90.0 + 180.0 * v / (side - 1), lon = -180.0 + 360.0 * u / (side - 1);
      if (lat < -20 || lat > 25 || lon < 30 || lon > 100) continue;
      const Eigen::Vector3d p = t.chart().position(u, v, t.height(u, v));
      worst = std::max(worst, distanceToMesh(p, m));
    }
  EXPECT_LE(worst, o.maxErrorM);
  o.regionDeg = std::array<double, 4>{10.0, 170.0, 20.0, -170.0};
  EXPECT_THROW(io::exportTinFromFile(dir / "p.planet", io::ImportOptions{}, dir / "x.obj",
                                     io::ExportFormat::kObj, o, notes),
               core::InputError)
      << "across the seam";
}

TEST(TinExport, WebDemTilesDecodeTheirPackedHeights) {
  const fs::path dir = testkit::freshDir("tin_webdem");
  // 1234.5 m: Terrain-RGB (1234.5 + 10000) / 0.1 = 112345 = 1 * 65536 + 182 * 256 + 217;
  // Terrarium 1234.5 + 32768 = 34002.5 = 132 * 256 + 210 + 128 / 256.
  cv::Mat rgb(2, 3, CV_8UC3, cv::Scalar(217, 182, 1));  // OpenCV stores B, G, R
  cv::imwrite((dir / "mapbox.png").string(), rgb);
  cv::Mat terrarium(2, 3, CV_8UC3, cv::Scalar(128, 210, 132));
  cv::imwrite((dir / "terrarium.png").string(), terrarium);
  const io::HeightImage a =
      io::readHeightImage(dir / "mapbox.png", io::PngHeightEncoding::kTerrainRgb);
  const io::HeightImage b =
      io::readHeightImage(dir / "terrarium.png", io::PngHeightEncoding::kTerrarium);
  ASSERT_EQ(a.values.size(), 6u);
  for (const float x : a.values) EXPECT_NEAR(x, 1234.5, 1e-3);
  for (const float x : b.values) EXPECT_NEAR(x, 1234.5, 1e-3);
  // Without --encoding an RGB tile is refused with the hint; a grey PNG is refused with one.
  try {
    io::readHeightImage(dir / "mapbox.png");
    ADD_FAILURE() << "an RGB PNG was read as a grey heightmap";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--encoding terrain-rgb"), std::string::npos) << e.what();
  }
  cv::imwrite((dir / "grey.png").string(), cv::Mat(2, 2, CV_8UC1, cv::Scalar(7)));
  EXPECT_THROW(io::readHeightImage(dir / "grey.png", io::PngHeightEncoding::kTerrarium),
               core::InputError);
  EXPECT_EQ(io::pngHeightEncodingFromString("terrain-rgb"), io::PngHeightEncoding::kTerrainRgb);
  EXPECT_THROW(io::pngHeightEncodingFromString("rgb"), core::InputError);
}

TEST(TinExport, RefusesBadRequestsNamingTheProblemAndWritesNothing) {
  const fs::path dir = testkit::freshDir("tin_bad");
  const fs::path png = writeRelief(dir, 20, 16, 5);
  auto expectRefused = [&](io::TinExportOptions o, const std::string& expected) {
    std::vector<std::string> notes;
    try {
      io::exportTinFromFile(png, heightmapOptions(1.0), dir / "out.obj", io::ExportFormat::kObj, o,
                            notes);
      ADD_FAILURE() << "accepted; expected: " << expected;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "out.obj"));
  };
  io::TinExportOptions o;
  o.maxErrorM = 0;
  expectRefused(o, "above 0");
  o.maxErrorM = 1;
  o.minAngleDeg = 40;
  expectRefused(o, "minimum angle 40");
  o.minAngleDeg = 0;
  o.controlErrorM = 0.2;
  expectRefused(o, "go together");
  cv::imwrite((dir / "small.png").string(), cv::Mat(8, 8, CV_8UC1, cv::Scalar(255)));
  o.controlMap = dir / "small.png";
  expectRefused(o, "small.png: the control map is 8x8 pixels; it must match the 20x16");
  std::vector<std::string> notes;
  EXPECT_THROW(
      io::exportTinFromFile(png, heightmapOptions(1.0), dir / "out.png", io::ExportFormat::kPng16,
                            io::TinExportOptions{.maxErrorM = 1}, notes),
      core::InputError);
}

TEST(TinExport, AGeoreferencedControlMapMustLieWhereTheHeightmapDoes) {
  const fs::path dir = testkit::freshDir("tin_control_geo");
  const core::GridSize g(5);  // 33^2
  auto tiff = [&](double spacing, double scale, const std::string& file) {
    std::vector<float> h(g.count());
    for (int v = 0; v <= g.m(); ++v)
      for (int u = 0; u <= g.m(); ++u)
        h[g.index(u, v)] = float(scale * (0.5 + 0.5 * std::sin(0.3 * u) * std::cos(0.2 * v)));
    const terrain::Terrain t(std::make_shared<core::FlatChart>(g, spacing, spacing), h);
    io::exportTerrain(t, dir / file, io::ExportOptions{});
  };
  tiff(30.0, 400.0, "dem.tif");
  tiff(30.0, 1.0, "same.tif");   // values 0..1, the heightmap's pixels
  tiff(10.0, 1.0, "other.tif");  // the same size, another pixel size
  io::ImportOptions h;
  h.chart = io::ChartKind::kFlat;
  io::TinExportOptions o;
  o.maxErrorM = 20;
  o.controlErrorM = 2;
  o.controlMap = dir / "same.tif";
  std::vector<std::string> notes;
  const nlohmann::json s =
      io::exportTinFromFile(dir / "dem.tif", h, dir / "a.obj", io::ExportFormat::kObj, o, notes);
  EXPECT_LE(s["measured_error_ratio"].get<double>(), 1.0);
  o.controlMap = dir / "other.tif";
  try {
    io::exportTinFromFile(dir / "dem.tif", h, dir / "b.obj", io::ExportFormat::kObj, o, notes);
    ADD_FAILURE() << "a control map with another pixel size was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("other.tif: the control map's georeferencing"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "b.obj"));
}

TEST(TinExport, AControlMapHoldsItsTighterErrorWhereItIsWhite) {
  const fs::path dir = testkit::freshDir("tin_control");
  const int w = 40, h = 30;
  const fs::path png = writeRelief(dir, w, h, 8);
  cv::Mat control(h, w, CV_8UC1, cv::Scalar(0));
  control(cv::Rect(5, 5, 15, 12)).setTo(255);
  cv::imwrite((dir / "control.png").string(), control);
  io::TinExportOptions o;
  o.maxErrorM = 8;
  o.controlMap = dir / "control.png";
  o.controlErrorM = 0.5;
  std::vector<std::string> notes;
  const nlohmann::json s = io::exportTinFromFile(png, heightmapOptions(1.0), dir / "c.ply",
                                                 io::ExportFormat::kPly, o, notes);
  EXPECT_LE(s["measured_error_ratio"].get<double>(), 1.0);
  io::TinExportOptions uniform;
  uniform.maxErrorM = 0.5;
  const nlohmann::json fine = io::exportTinFromFile(png, heightmapOptions(1.0), dir / "f.ply",
                                                    io::ExportFormat::kPly, uniform, notes);
  EXPECT_LT(s["triangles"].get<std::size_t>(), fine["triangles"].get<std::size_t>());
}

}  // namespace
