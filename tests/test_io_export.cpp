// Exports: meshes whose written coordinates stay within the requested error of every
// full-resolution vertex (OBJ, PLY, GLB), well-formed GLB, heightmap exports, the flat chart.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/chart_factory.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/octahedral_chart.hpp"
#include "fresh_dir.hpp"
#include "io/export.hpp"
#include "io/heightmap_export.hpp"
#include "io/heightmap_import.hpp"
#include "io/mesh_export.hpp"
#include "mesh_checks.hpp"
#include "terrain/error_mesher.hpp"
#include "terrain/screen_error.hpp"
#include "test_terrains.hpp"
#include "tin/tin_check.hpp"

using namespace ps;
namespace fs = std::filesystem;

namespace {

using testkit::readAll;

template <class T>
T le(const unsigned char* p) {
  T x;
  std::memcpy(&x, p, sizeof(T));
  return x;
}

// A rough flat terrain: ridges and bumps, metres.
terrain::Terrain flatTerrain(int n, double dx = 30.0, double amplitude = 800.0) {
  auto chart = std::make_shared<core::FlatChart>(core::GridSize(n), dx, dx);
  const int m = chart->grid().m();
  std::vector<float> h(chart->grid().count());
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const double x = double(u) / m, y = double(v) / m;
      h[chart->grid().index(u, v)] =
          float(amplitude * (0.5 * std::sin(9 * x + 2 * y) * std::cos(7 * y) +
                             0.3 * std::exp(-40 * ((x - 0.3) * (x - 0.3) + (y - 0.6) * (y - 0.6))) +
                             0.05 * std::sin(80 * x * y)));
    }
  }
  return terrain::Terrain(chart, std::move(h));
}

// Largest distance between a full-resolution vertex and the surface the written triangles
// span, where `written[i]` is mesh vertex i as read back from the file (planet frame).
double writtenMeshError(const terrain::Terrain& t, const terrain::Mesh& mesh,
                        const std::vector<Eigen::Vector3d>& written) {
  const auto side = std::uint64_t(t.grid().side());
  double worst = 0;
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    const std::uint32_t ia = mesh.indices[3 * k], ib = mesh.indices[3 * k + 1],
                        ic = mesh.indices[3 * k + 2];
    const auto grid = [&](std::uint32_t i) {
      return std::pair<int, int>(int(mesh.gridIndex[i] % side), int(mesh.gridIndex[i] / side));
    };
    const auto [au, av] = grid(ia);
    const auto [bu, bv] = grid(ib);
    const auto [cu, cv] = grid(ic);
    const long long e0u = bu - au, e0v = bv - av, e1u = cu - au, e1v = cv - av;
    const long long len2 = e0u * e0u + e0v * e0v;
    for (int v = std::min({av, bv, cv}); v <= std::max({av, bv, cv}); ++v) {
      for (int u = std::min({au, bu, cu}); u <= std::max({au, bu, cu}); ++u) {
        const long long da = (u - au) * e0u + (v - av) * e0v, db = (u - au) * e1u + (v - av) * e1v;
        if (da < 0 || db < 0 || da + db > len2) continue;
        const double wb = double(da) / double(len2), wc = double(db) / double(len2);
        const Eigen::Vector3d onMesh =
            (1 - wb - wc) * written[ia] + wb * written[ib] + wc * written[ic];
        worst = std::max(worst, (t.chart().position(u, v, t.height(u, v)) - onMesh).norm());
      }
    }
  }
  return worst;
}

// A flat mesh is conforming when every edge has a partner of opposite direction, except edges
// along the grid's border.
std::string flatConformityDefect(const terrain::Terrain& t, const terrain::Mesh& mesh) {
  const auto side = std::uint64_t(t.grid().side());
  const int m = t.grid().m();
  std::map<std::pair<std::uint64_t, std::uint64_t>, int> directed;
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    const std::uint64_t a = mesh.gridIndex[mesh.indices[3 * k]],
                        b = mesh.gridIndex[mesh.indices[3 * k + 1]],
                        c = mesh.gridIndex[mesh.indices[3 * k + 2]];
    for (auto e : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      if (++directed[e] > 1) return "directed edge used twice";
    }
  }
  for (const auto& [e, n] : directed) {
    if (directed.count({e.second, e.first})) continue;
    const int u0 = int(e.first % side), v0 = int(e.first / side), u1 = int(e.second % side),
              v1 = int(e.second / side);
    const bool border = (u0 == u1 && (u0 == 0 || u0 == m)) || (v0 == v1 && (v0 == 0 || v0 == m));
    if (!border) return "interior edge without a partner: a crack or T-junction";
  }
  return "";
}

struct ReadMesh {
  std::vector<Eigen::Vector3d> positions, normals;  // planet frame
  std::vector<std::uint32_t> indices;
};

ReadMesh readGlb(const fs::path& p) {
  const auto b = readAll(p);
  ReadMesh r;
  EXPECT_GE(b.size(), 28u);
  EXPECT_EQ(le<std::uint32_t>(b.data()), 0x46546C67u);
  EXPECT_EQ(le<std::uint32_t>(b.data() + 4), 2u);
  EXPECT_EQ(le<std::uint32_t>(b.data() + 8), b.size());
  const std::uint32_t jsonLen = le<std::uint32_t>(b.data() + 12);
  EXPECT_EQ(le<std::uint32_t>(b.data() + 16), 0x4E4F534Au);
  EXPECT_EQ(jsonLen % 4, 0u);
  const auto gltf = nlohmann::json::parse(std::string(b.begin() + 20, b.begin() + 20 + jsonLen));
  const unsigned char* binHeader = b.data() + 20 + jsonLen;
  const std::uint32_t binLen = le<std::uint32_t>(binHeader);
  EXPECT_EQ(le<std::uint32_t>(binHeader + 4), 0x004E4942u);
  EXPECT_EQ(20 + jsonLen + 8 + binLen, b.size());
  EXPECT_EQ(gltf["buffers"][0]["byteLength"].get<std::uint32_t>(), binLen);
  EXPECT_EQ(gltf["asset"]["version"], "2.0");
  const unsigned char* bin = binHeader + 8;
  const auto& prim = gltf["meshes"][0]["primitives"][0];
  auto view = [&](int accessor) {
    const auto& a = gltf["accessors"][accessor];
    const auto& v = gltf["bufferViews"][a["bufferView"].get<int>()];
    return std::pair<const unsigned char*, std::size_t>(bin + v["byteOffset"].get<std::size_t>(),
                                                        a["count"].get<std::size_t>());
  };
  const int posAcc = prim["attributes"]["POSITION"], nrmAcc = prim["attributes"]["NORMAL"],
            idxAcc = prim["indices"];
  const auto [pos, nv] = view(posAcc);
  const auto [nrm, nn] = view(nrmAcc);
  const auto [idx, ni] = view(idxAcc);
  EXPECT_EQ(nv, nn);
  EXPECT_EQ(gltf["accessors"][idxAcc]["componentType"], 5125);
  const auto& lo = gltf["accessors"][posAcc]["min"];
  const auto& hi = gltf["accessors"][posAcc]["max"];
  for (std::size_t i = 0; i < nv; ++i) {
    const float x = le<float>(pos + 12 * i), y = le<float>(pos + 12 * i + 4),
                z = le<float>(pos + 12 * i + 8);
    for (int k = 0; k < 3; ++k) {
      const float c = k == 0 ? x : k == 1 ? y : z;
      EXPECT_GE(c, lo[k].get<float>());
      EXPECT_LE(c, hi[k].get<float>());
    }
    r.positions.emplace_back(x, -double(z), y);  // glTF +Y up -> planet frame
    r.normals.emplace_back(le<float>(nrm + 12 * i), -double(le<float>(nrm + 12 * i + 8)),
                           le<float>(nrm + 12 * i + 4));
  }
  for (std::size_t i = 0; i < ni; ++i) {
    r.indices.push_back(le<std::uint32_t>(idx + 4 * i));
    EXPECT_LT(r.indices.back(), nv);
  }
  return r;
}

ReadMesh readPly(const fs::path& p) {
  const auto b = readAll(p);
  const std::string text(b.begin(), b.end());
  const std::size_t end = text.find("end_header\n");
  EXPECT_NE(end, std::string::npos);
  std::istringstream header(text.substr(0, end));
  std::size_t nv = 0, nf = 0;
  std::string line;
  while (std::getline(header, line)) {
    if (line.rfind("element vertex ", 0) == 0) nv = std::stoul(line.substr(15));
    if (line.rfind("element face ", 0) == 0) nf = std::stoul(line.substr(13));
  }
  EXPECT_NE(text.find("format binary_little_endian 1.0"), std::string::npos);
  const unsigned char* d = b.data() + end + 11;
  EXPECT_EQ(b.size(), end + 11 + nv * 24 + nf * 13);
  ReadMesh r;
  for (std::size_t i = 0; i < nv; ++i, d += 24) {
    r.positions.emplace_back(le<float>(d), le<float>(d + 4), le<float>(d + 8));
    r.normals.emplace_back(le<float>(d + 12), le<float>(d + 16), le<float>(d + 20));
  }
  for (std::size_t k = 0; k < nf; ++k, d += 13) {
    EXPECT_EQ(d[0], 3);
    for (int j = 0; j < 3; ++j) r.indices.push_back(std::uint32_t(le<std::int32_t>(d + 1 + 4 * j)));
  }
  return r;
}

ReadMesh readObj(const fs::path& p) {
  std::ifstream f(p);
  ReadMesh r;
  std::string tag;
  while (f >> tag) {
    if (tag == "v") {
      double x, y, z;
      f >> x >> y >> z;
      r.positions.emplace_back(x, y, z);
    } else if (tag == "f") {
      for (int j = 0; j < 3; ++j) {
        std::uint32_t i;
        f >> i;
        r.indices.push_back(i - 1);
      }
    } else {
      std::getline(f, tag);
    }
  }
  return r;
}

void checkWrittenMeshes(const terrain::Terrain& t, const std::vector<double>& errors,
                        const std::string& label) {
  const fs::path dir = testkit::freshDir("io_mesh_" + label);
  for (const auto format : {io::MeshFormat::kObj, io::MeshFormat::kPly, io::MeshFormat::kGlb}) {
    for (const double maxErr : errors) {
      const fs::path file = dir / ("m." + io::toString(format));
      terrain::Mesh mesh;
      const auto rep = io::exportMesh(t, maxErr, format, file, &mesh);
      const std::string what =
          label + " " + io::toString(format) + " at " + std::to_string(maxErr) + " m";
      EXPECT_LE(rep.meshedErrorM, maxErr) << what;
      const terrain::Mesh welded = io::weldMesh(t, mesh);
      EXPECT_EQ(rep.triangles, welded.triangleCount());
      EXPECT_EQ(rep.vertices, welded.gridIndex.size());
      // The mesh the error hierarchy chose, in double: within what it was asked for.
      EXPECT_LE(terrain::measureTrueError(t, mesh), rep.meshedErrorM) << what;
      EXPECT_EQ(t.chart().hasPoleRows() ? testkit::conformityDefect(t, mesh)
                                        : flatConformityDefect(t, mesh),
                "")
          << what;
      // The file as written (float32 / 4 decimals): within the user's request.
      const ReadMesh r = format == io::MeshFormat::kObj   ? readObj(file)
                         : format == io::MeshFormat::kPly ? readPly(file)
                                                          : readGlb(file);
      ASSERT_EQ(r.positions.size(), welded.gridIndex.size()) << what;
      ASSERT_EQ(r.indices, welded.indices) << what;
      // Each vertex of the mesh before welding takes its welded vertex's written position.
      std::map<std::uint64_t, std::size_t> writtenAt;
      for (std::size_t i = 0; i < welded.gridIndex.size(); ++i) writtenAt[welded.gridIndex[i]] = i;
      std::vector<Eigen::Vector3d> perVertex;
      const auto side = std::uint64_t(t.grid().side());
      for (const std::uint64_t gi : mesh.gridIndex) {
        const core::GridPoint p = t.chart().canonical(int(gi % side), int(gi / side));
        perVertex.push_back(
            r.positions[writtenAt.at(std::uint64_t(p.v) * side + std::uint64_t(p.u))]);
      }
      EXPECT_LE(writtenMeshError(t, mesh, perVertex), maxErr) << what;
      // Welded: a planet is a closed 2-manifold (Euler 2); a flat map a disc whose border edges
      // lie on the grid's border.
      std::vector<std::array<std::uint32_t, 3>> triangles;
      std::size_t noArea = 0;
      for (std::size_t k = 0; k + 2 < r.indices.size(); k += 3) {
        triangles.push_back({r.indices[k], r.indices[k + 1], r.indices[k + 2]});
        const Eigen::Vector3d &a = r.positions[r.indices[k]], &b = r.positions[r.indices[k + 1]],
                              &c = r.positions[r.indices[k + 2]];
        noArea += !((b - a).cross(c - a).norm() > 0);
      }
      const tin::MeshTopology topo = tin::meshTopology(r.positions.size(), triangles);
      EXPECT_EQ(topo.nonManifoldEdges, 0u) << what;
      EXPECT_EQ(topo.degenerate, 0u) << what;
      EXPECT_EQ(noArea, 0u) << what;
      EXPECT_EQ(topo.euler(), t.chart().sphereRadius() > 0 ? 2 : 1) << what;
      if (t.chart().sphereRadius() > 0) {
        EXPECT_EQ(topo.borderEdges, 0u) << what;
      } else {
        // Every edge used once runs along the grid's border.
        std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
        for (const auto& tri : triangles)
          for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = tri[std::size_t(e)], b = tri[std::size_t((e + 1) % 3)];
            ++uses[{std::min(a, b), std::max(a, b)}];
          }
        const int m = t.grid().m();
        for (const auto& [edge, count] : uses) {
          if (count != 1) continue;
          const std::uint64_t ga = welded.gridIndex[edge.first], gb = welded.gridIndex[edge.second];
          const int au = int(ga % side), av = int(ga / side), bu = int(gb % side),
                    bv = int(gb / side);
          const bool alongBorder =
              (au == bu && (au == 0 || au == m)) || (av == bv && (av == 0 || av == m));
          EXPECT_TRUE(alongBorder)
              << what << ": (" << au << "," << av << ")-(" << bu << "," << bv << ")";
        }
      }
      for (const auto& n : r.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-5) << what;
    }
  }
  fs::remove_all(dir);
}

}  // namespace

TEST(IoExport, PlanetMeshesAsWrittenStayWithinTheRequestedError) {
  const auto t = testkit::bumpyTerrain(6, 9, 12000.0);
  checkWrittenMeshes(t, {400.0}, "latlong");
}

TEST(IoExport, FlatMeshesAsWrittenStayWithinTheRequestedError) {
  const auto t = flatTerrain(6);
  checkWrittenMeshes(t, {2.0}, "flat");
  // Seen from +z, every triangle faces up (CCW in (u, v) is CCW from above).
  const auto mesh = terrain::meshToError(t, 2.0);
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    const auto& a = mesh.positions[mesh.indices[3 * k]];
    const auto& b = mesh.positions[mesh.indices[3 * k + 1]];
    const auto& c = mesh.positions[mesh.indices[3 * k + 2]];
    ASSERT_GT((b - a).cross(c - a).z(), 0.0f);
  }
}

TEST(IoExport, ZeroErrorFlatMeshIsTheFullGridAndExact) {
  const auto t = flatTerrain(5, 10.0, 100.0);
  const auto mesh = terrain::meshToError(t, 0.0);
  EXPECT_EQ(mesh.triangleCount(), std::size_t(2 * 32 * 32));
  EXPECT_EQ(terrain::measureTrueError(t, mesh), 0.0);
}

// Normals point outward, and the seam and each pole are one vertex each (one normal there: no
// shading seam), as Chart::canonical says.
TEST(IoExport, GlbNormalsPointOutwardAndTheSeamIsOneVertex) {
  const auto t = testkit::bumpyTerrain(6, 2, 3000.0);
  const fs::path dir = testkit::freshDir("io_glbnormals");
  terrain::Mesh mesh;
  io::exportMesh(t, 5000.0, io::MeshFormat::kGlb, dir / "p.glb", &mesh);
  const ReadMesh r = readGlb(dir / "p.glb");
  const terrain::Mesh welded = io::weldMesh(t, mesh);  // what the file holds
  ASSERT_EQ(r.normals.size(), welded.gridIndex.size());
  const auto side = std::uint64_t(t.grid().side());
  const int m = t.grid().m();
  int seamVertices = 0, poleVertices = 0;
  for (std::size_t i = 0; i < r.normals.size(); ++i) {
    const int u = int(welded.gridIndex[i] % side), v = int(welded.gridIndex[i] / side);
    EXPECT_GT(r.normals[i].dot(t.chart().up(u, v)), 0.3) << "(" << u << "," << v << ")";
    EXPECT_NE(u, m) << "column m is column 0";
    seamVertices += u == 0 && v > 0 && v < m;
    if (v == 0 || v == m) {
      ++poleVertices;
      EXPECT_EQ(u, 0);
    }
  }
  EXPECT_GT(seamVertices, 0);
  EXPECT_EQ(poleVertices, 2);
  fs::remove_all(dir);
}

TEST(IoExport, BadRequestsAreRefused) {
  const auto t = testkit::bumpyTerrain(5, 1, 1000.0);
  const fs::path dir = testkit::freshDir("io_badexport");
  // float32 cannot place a vertex of a 6,372 km planet closer than ~0.66 m.
  EXPECT_THROW(io::exportMesh(t, 0.1, io::MeshFormat::kGlb, dir / "x.glb"), core::InputError);
  EXPECT_NO_THROW(io::exportMesh(t, 0.1, io::MeshFormat::kObj, dir / "x.obj"));
  EXPECT_THROW(io::exportTerrain(t, dir / "x.glb", {}), core::InputError);  // no --max-error
  EXPECT_THROW(io::exportTerrain(t, dir / "x.xyz", {}), core::InputError);
  EXPECT_THROW(io::exportTerrain(t, dir / "noext", {}), core::InputError);
  io::ExportOptions o;
  o.maxErrorM = 10.0;
  EXPECT_THROW(io::exportTerrain(t, dir / "x.png", o), core::InputError);  // error on a heightmap
  EXPECT_THROW(io::exportFormatFromName("jpeg"), core::InputError);
  fs::remove_all(dir);
}

TEST(IoExport, FlatHeightmapsAtGridSizeAreExactAndCarryTheirSpacing) {
  const auto t = flatTerrain(6, 25.0);
  const fs::path dir = testkit::freshDir("io_flatmaps");
  for (const char* ext : {"raw", "tif", "png"}) {
    const fs::path file = dir / (std::string("h.") + ext);
    io::exportTerrain(t, file, {});
    io::ImportOptions o;
    o.chart = io::ChartKind::kFlat;
    const auto r = io::importHeightmap(file, o);
    const auto* flat = dynamic_cast<const core::FlatChart*>(r.planet.chart.get());
    ASSERT_NE(flat, nullptr);
    EXPECT_DOUBLE_EQ(flat->dx(), 25.0) << ext;
    EXPECT_DOUBLE_EQ(flat->dy(), 25.0) << ext;
    ASSERT_EQ(r.planet.heights.size(), t.heights().size());
    const double tol =
        std::string(ext) == "png" ? (t.maxHeight() - t.minHeight()) / 65535.0 * 0.51 : 0.0;
    double worst = 0;
    for (std::size_t i = 0; i < r.planet.heights.size(); ++i) {
      worst = std::max(worst, std::abs(double(r.planet.heights[i]) - double(t.heights()[i])));
    }
    EXPECT_LE(worst, tol) << ext;
    const auto side = nlohmann::json::parse(std::ifstream(file.string() + ".json"));
    EXPECT_EQ(side["projection"], "flat");
  }
  fs::remove_all(dir);
}

TEST(IoExport, EquirectangularExportsOfAnySizeReimportCloseToThePlanet) {
  // A smooth planet, so resampling (export, then import) adds little.
  auto chart = std::make_shared<core::LatLongChart>(core::GridSize(7), 3389500.0);  // Mars
  const int m = chart->grid().m();
  std::vector<float> h(chart->grid().count());
  for (int v = 0; v <= m; ++v) {
    for (int u = 0; u <= m; ++u) {
      const Eigen::Vector3d d = chart->direction(u, v);
      h[chart->grid().index(u, v)] = float(3000.0 * d.x() * d.z() + 1500.0 * d.y());
    }
  }
  const terrain::Terrain t(chart, h);
  const fs::path dir = testkit::freshDir("io_equirect");
  for (const char* ext : {"tif", "raw", "png"}) {
    const fs::path file = dir / (std::string("e.") + ext);
    io::ExportOptions eo;
    eo.width = 512;
    eo.height = 256;
    io::exportTerrain(t, file, eo);
    io::ImportOptions o;
    o.gridSide = m + 1;
    const auto r = io::importHeightmap(file, o);
    double worst = 0;
    for (std::size_t i = 0; i < h.size(); ++i)
      worst = std::max(worst, std::abs(double(r.planet.heights[i]) - h[i]));
    EXPECT_LT(worst, 60.0) << ext;  // of +-4500 m relief, after two bilinear resamplings
    EXPECT_NO_THROW(terrain::Terrain::validateHeights(*r.planet.chart, r.planet.heights));
    if (std::string(ext) != "png") {
      // The GeoTIFF's sphere and the raw sidecar's radius_m carry the planet's radius.
      EXPECT_EQ(r.planet.chart->sphereRadius(), 3389500.0) << ext;
    }
  }
  fs::remove_all(dir);
}

// The octahedral chart has no rows of latitude: an equirectangular export reads each pixel's
// direction through the chart's inverse (across the folds near the grid's sides), and an import
// samples the image at each grid vertex's direction. A smooth field, exported and compared with
// the field itself pixel by pixel, then imported back and compared vertex by vertex.
TEST(IoExport, OctahedralPlanetsExportAndReimportEquirectangular) {
  const auto field = [](const Eigen::Vector3d& d) {
    return 3000.0 * d.x() * d.z() + 1500.0 * d.y() + 800.0 * d.z() * d.z();
  };
  for (const auto mapping :
       {core::OctahedralChart::Mapping::kEqualArea, core::OctahedralChart::Mapping::kCentral}) {
    auto chart = std::make_shared<core::OctahedralChart>(core::GridSize(7), 3389500.0, mapping);
    const int m = chart->grid().m();
    std::vector<float> h(chart->grid().count());
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) h[chart->grid().index(u, v)] = float(field(chart->up(u, v)));
    const terrain::Terrain t(chart, h);
    for (const auto how : {io::Interpolation::kBilinear, io::Interpolation::kCubic}) {
      const io::Raster r = io::resampleEquirectangular(t, 512, 256, how);
      double worst = 0;
      for (int y = 0; y < r.height; ++y) {
        const double lat = M_PI * (0.5 - (y + 0.5) / r.height);
        for (int x = 0; x < r.width; ++x) {
          const double lon = M_PI * (2.0 * (x + 0.5) / r.width - 1.0);
          const Eigen::Vector3d d(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                                  std::sin(lat));
          worst = std::max(worst, std::abs(r.metres[std::size_t(y * r.width + x)] - field(d)));
        }
      }
      // 129^2 vertices about 3 degrees apart over a field of +-4,500 m: interpolation's error
      // (cubic's is larger: the map from the square bends at the creases). Measured 10.3 and
      // 14.3 m (equal area), 2.6 and 8.3 m (central); reading the cubic stencil across a side
      // without its mirror in v gives 18.3 and 12.4 m.
      EXPECT_LT(worst, how == io::Interpolation::kCubic ? 16.0 : 12.0)
          << chart->name() << " " << io::toString(how);
      std::printf("%s export, %s: worst %.2f m\n", chart->name().c_str(), io::toString(how).c_str(),
                  worst);
    }
    const fs::path dir = testkit::freshDir("io_octa_equirect");
    io::ExportOptions eo;
    eo.width = 512;
    eo.height = 256;
    io::exportTerrain(t, dir / "e.tif", eo);
    io::ImportOptions o;
    o.chart = core::shapeOf(*chart);
    o.gridSide = m + 1;
    const auto back = io::importHeightmap(dir / "e.tif", o);
    ASSERT_EQ(back.planet.chart->name(), chart->name());
    EXPECT_EQ(back.planet.chart->sphereRadius(), 3389500.0);
    EXPECT_NO_THROW(terrain::Terrain::validateHeights(*back.planet.chart, back.planet.heights));
    double worst = 0;
    for (std::size_t i = 0; i < h.size(); ++i)
      worst = std::max(worst, std::abs(double(back.planet.heights[i]) - h[i]));
    EXPECT_LT(worst, 60.0) << chart->name();
    std::printf("%s export and import: worst %.2f m\n", chart->name().c_str(), worst);
    fs::remove_all(dir);
  }
}

// A torus and a cylinder export their own (u, v) grid: at the grid's size every pixel is one
// vertex and the image comes back onto the same grid bit for bit (raw and TIFF), its dimensions
// from the raw sidecar; at another size it is a periodic resampling that stays close to a smooth
// field; a file that maps one surface is refused onto another.
TEST(IoExport, TorusAndCylinderHeightmapsAreTheirGridAndComeBackExactly) {
  const core::GridSize g(6);
  const int m = g.m();
  for (const core::ChartShape shape : {core::ChartShape::kTorus, core::ChartShape::kCylinder}) {
    const bool torus = shape == core::ChartShape::kTorus;
    core::ChartDims dims;
    dims.radius = 3000.0;
    dims.minorRadius = torus ? 1000.0 : 0.0;
    dims.length = torus ? 0.0 : 5000.0;
    const auto chart = core::makeChart(shape, g, dims);
    // Smooth and periodic round the axis (and round the tube on the torus): whole waves in u, v.
    const auto field = [&](double u, double v) {
      const double a = 2 * M_PI * u / m, b = (torus ? 2 * M_PI : M_PI) * v / m;
      return 120.0 * std::sin(a) * std::cos(b) + 50.0 * std::cos(3 * a + (torus ? b : 0.0));
    };
    std::vector<float> h(g.count());
    for (int v = 0; v <= m; ++v)
      for (int u = 0; u <= m; ++u) {
        const core::GridPoint c = chart->canonical(u, v);
        h[g.index(u, v)] = float(field(c.u, c.v));
      }
    const terrain::Terrain t(chart, h);
    const fs::path dir = testkit::freshDir(std::string("io_tube_") + chart->name());
    for (const char* ext : {"raw", "tif"}) {
      const fs::path file = dir / (std::string("h.") + ext);
      const auto summary = io::exportTerrain(t, file, {});
      EXPECT_EQ(summary["width"], m) << ext;
      EXPECT_EQ(summary["height"], torus ? m : m + 1) << ext;
      io::ImportOptions o;
      o.chart = shape;
      if (std::string(ext) == "tif") {  // a TIFF names no dimensions: the user does
        o.radius = dims.radius;
        if (torus) o.minorRadius = dims.minorRadius;
        if (!torus) o.length = dims.length;
      }
      const auto r = io::importHeightmap(file, o);
      ASSERT_EQ(r.planet.chart->name(), chart->name()) << ext;
      EXPECT_EQ(core::dimsOf(*r.planet.chart).radius, dims.radius);
      EXPECT_EQ(core::dimsOf(*r.planet.chart).minorRadius, dims.minorRadius);
      EXPECT_EQ(core::dimsOf(*r.planet.chart).length, dims.length);
      ASSERT_EQ(r.planet.heights.size(), h.size());
      std::size_t different = 0;
      for (std::size_t i = 0; i < h.size(); ++i) different += r.planet.heights[i] != h[i];
      EXPECT_EQ(different, 0u) << chart->name() << " " << ext;
    }
    // Another size: resampled both ways (periodically), close to the field.
    io::ExportOptions eo;
    eo.width = 3 * m / 2;
    io::exportTerrain(t, dir / "big.raw", eo);
    io::ImportOptions o;
    o.chart = shape;
    o.gridSide = m + 1;
    const auto back = io::importHeightmap(dir / "big.raw", o);
    EXPECT_NO_THROW(terrain::Terrain::validateHeights(*back.planet.chart, back.planet.heights));
    double worst = 0;
    for (std::size_t i = 0; i < h.size(); ++i)
      worst = std::max(worst, std::abs(double(back.planet.heights[i]) - h[i]));
    EXPECT_LT(worst, 0.05) << chart->name();  // of +-170 m, 64 cells a wave: 0.008, 0.011
    std::printf("%s: through a %d-column image and back, worst %.3f m\n", chart->name().c_str(),
                eo.width, worst);
    // A file that maps this surface goes onto this chart only, and needs its dimensions.
    io::ImportOptions sphere;
    EXPECT_THROW(io::importHeightmap(dir / "h.raw", sphere), core::InputError);
    io::ImportOptions other;
    other.chart = torus ? core::ChartShape::kCylinder : core::ChartShape::kTorus;
    EXPECT_THROW(io::importHeightmap(dir / "h.raw", other), core::InputError);
    io::ImportOptions bare;
    bare.chart = shape;
    EXPECT_THROW(io::importHeightmap(dir / "h.tif", bare), core::InputError);  // no radius
    fs::remove_all(dir);
  }
}

TEST(IoFlatChart, PositionsInverseAndLimits) {
  const core::FlatChart c(core::GridSize(5), 2.0, 3.0);
  EXPECT_EQ(c.position(4, 5, 7.0), Eigen::Vector3d(8.0, 15.0, 7.0));
  EXPECT_EQ(c.positionAt(0.5, 1.5, -1.0), Eigen::Vector3d(1.0, 4.5, -1.0));
  EXPECT_EQ(c.up(3, 3), Eigen::Vector3d::UnitZ());
  EXPECT_EQ(*c.inverse({8.0, 15.0, 100.0}), Eigen::Vector2d(4.0, 5.0));
  EXPECT_EQ(*c.inverse({-8.0, 1e9, 0.0}), Eigen::Vector2d(0.0, 32.0));
  EXPECT_FALSE(c.wrapsU());
  EXPECT_FALSE(c.hasPoleRows());
  EXPECT_EQ(c.sphereRadius(), 0.0);
  EXPECT_GT(c.heightLimit(), 1e5);
  EXPECT_THROW(core::FlatChart(core::GridSize(5), 0.0, 1.0), core::InputError);
  EXPECT_THROW(core::FlatChart(core::GridSize(5), 1.0, NAN), core::InputError);
}
