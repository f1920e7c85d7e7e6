#include "io/mesh_export.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <unordered_map>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "io/atomic_file.hpp"
#include "terrain/error_mesher.hpp"

namespace ps::io {

void writeObj(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
              const std::filesystem::path& path) {
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp);
    f << "# PlanetSculpt view mesh: " << mesh.gridIndex.size() << " vertices, "
      << mesh.triangleCount() << " triangles, metres, planet frame\n";
    const auto side = std::uint64_t(terrain.grid().side());
    char line[128];
    for (const auto gi : mesh.gridIndex) {
      const int u = int(gi % side), v = int(gi / side);
      const Eigen::Vector3d p = terrain.chart().position(u, v, terrain.height(u, v));
      std::snprintf(line, sizeof line, "v %.4f %.4f %.4f\n", p.x(), p.y(), p.z());
      f << line;
    }
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
      f << "f " << mesh.indices[3 * t] + 1 << ' ' << mesh.indices[3 * t + 1] + 1 << ' '
        << mesh.indices[3 * t + 2] + 1 << '\n';
    }
    if (!f) throw std::runtime_error("cannot write " + path.string());
  });
}

namespace {

Eigen::Vector3d gridPosition(const terrain::Terrain& t, std::uint64_t gi) {
  const auto side = std::uint64_t(t.grid().side());
  const int u = int(gi % side), v = int(gi / side);
  return t.chart().position(u, v, t.height(u, v));
}

// Seam twins and pole rows are one surface point: one key each.
std::uint64_t canonicalVertex(const terrain::Terrain& t, std::uint64_t gi) {
  const auto side = std::uint64_t(t.grid().side());
  const std::uint64_t m = side - 1;
  std::uint64_t u = gi % side, v = gi / side;
  if (t.chart().hasPoleRows() && (v == 0 || v == m)) u = 0;
  if (t.chart().wrapsU() && u == m) u = 0;
  return v * side + u;
}

template <class T>
void appendLe(std::vector<unsigned char>& out, T x) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &x, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

void writeBytes(const std::vector<unsigned char>& bytes, const std::filesystem::path& path) {
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    f.close();
    if (!f) throw std::runtime_error("cannot write " + path.string() + " (disk full?)");
  });
}

}  // namespace

std::vector<Eigen::Vector3f> vertexNormals(const terrain::Terrain& t, const terrain::Mesh& mesh) {
  std::unordered_map<std::uint64_t, Eigen::Vector3d> sum;
  sum.reserve(mesh.gridIndex.size());
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    const std::uint64_t g[3] = {mesh.gridIndex[mesh.indices[3 * k]],
                                mesh.gridIndex[mesh.indices[3 * k + 1]],
                                mesh.gridIndex[mesh.indices[3 * k + 2]]};
    const Eigen::Vector3d a = gridPosition(t, g[0]), b = gridPosition(t, g[1]),
                          c = gridPosition(t, g[2]);
    const Eigen::Vector3d n = (b - a).cross(c - a);  // |n| = twice the area
    for (const auto gi : g) {
      auto [it, fresh] = sum.try_emplace(canonicalVertex(t, gi), Eigen::Vector3d::Zero());
      it->second += n;
    }
  }
  std::vector<Eigen::Vector3f> out(mesh.gridIndex.size());
  const auto side = std::uint64_t(t.grid().side());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::uint64_t gi = mesh.gridIndex[i];
    Eigen::Vector3d n = sum[canonicalVertex(t, gi)];
    if (!(n.norm() > 0)) n = t.chart().up(int(gi % side), int(gi / side));
    out[i] = n.normalized().cast<float>();
  }
  return out;
}

void writePly(const terrain::Terrain& t, const terrain::Mesh& mesh,
              const std::filesystem::path& path) {
  const auto normals = vertexNormals(t, mesh);
  std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment PlanetSculpt mesh, metres, planet frame (z "
      "up)\n";
  header += "element vertex " + std::to_string(mesh.gridIndex.size()) + "\n";
  for (const char* p : {"x", "y", "z", "nx", "ny", "nz"})
    header += std::string("property float ") + p + "\n";
  header += "element face " + std::to_string(mesh.triangleCount()) + "\n";
  header += "property list uchar int vertex_indices\nend_header\n";
  std::vector<unsigned char> out(header.begin(), header.end());
  out.reserve(out.size() + mesh.gridIndex.size() * 24 + mesh.triangleCount() * 13);
  for (std::size_t i = 0; i < mesh.gridIndex.size(); ++i) {
    const Eigen::Vector3f p = gridPosition(t, mesh.gridIndex[i]).cast<float>();
    for (int k = 0; k < 3; ++k) appendLe<float>(out, p[k]);
    for (int k = 0; k < 3; ++k) appendLe<float>(out, normals[i][k]);
  }
  for (std::size_t k = 0; k < mesh.triangleCount(); ++k) {
    out.push_back(3);
    for (int j = 0; j < 3; ++j)
      appendLe<std::int32_t>(out, std::int32_t(mesh.indices[3 * k + std::size_t(j)]));
  }
  writeBytes(out, path);
}

void writeGlb(const terrain::Terrain& t, const terrain::Mesh& mesh,
              const std::filesystem::path& path, const std::string& extrasJson) {
  const std::size_t nv = mesh.gridIndex.size(), ni = mesh.indices.size();
  if (nv == 0 || ni == 0)
    throw std::invalid_argument("cannot write an empty mesh to " + path.string());
  const auto normals = vertexNormals(t, mesh);
  std::vector<unsigned char> bin;
  bin.reserve(nv * 24 + ni * 4);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY),
                  hi = Eigen::Vector3f::Constant(-INFINITY);
  for (std::size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3d p = gridPosition(t, mesh.gridIndex[i]);
    const Eigen::Vector3f q(float(p.x()), float(p.z()), float(-p.y()));  // +Y up
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
    for (int k = 0; k < 3; ++k) appendLe<float>(bin, q[k]);
  }
  for (std::size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3f& n = normals[i];
    appendLe<float>(bin, n.x());
    appendLe<float>(bin, n.z());
    appendLe<float>(bin, -n.y());
  }
  for (const std::uint32_t i : mesh.indices) appendLe<std::uint32_t>(bin, i);
  while (bin.size() % 4) bin.push_back(0);

  nlohmann::json extras = nlohmann::json::parse(extrasJson, nullptr, false);
  if (extras.is_discarded()) extras = nlohmann::json::object();
  const std::size_t posBytes = nv * 12, idxBytes = ni * 4;
  nlohmann::json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", "PlanetSculpt"}, {"extras", extras}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}, {"name", "planet"}}}},
      {"meshes",
       {{{"name", "planet"},
         {"primitives",
          {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"indices", 2}, {"mode", 4}}}}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", posBytes}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", posBytes}, {"byteLength", posBytes}, {"target", 34962}},
        {{"buffer", 0},
         {"byteOffset", 2 * posBytes},
         {"byteLength", idxBytes},
         {"target", 34963}}}},
      {"accessors",
       {{{"bufferView", 0},
         {"componentType", 5126},
         {"count", nv},
         {"type", "VEC3"},
         {"min", {lo.x(), lo.y(), lo.z()}},
         {"max", {hi.x(), hi.y(), hi.z()}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", nv}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5125}, {"count", ni}, {"type", "SCALAR"}}}}};
  std::string json = gltf.dump();
  while (json.size() % 4) json.push_back(' ');

  std::vector<unsigned char> out;
  out.reserve(12 + 8 + json.size() + 8 + bin.size());
  appendLe<std::uint32_t>(out, 0x46546C67u);  // "glTF"
  appendLe<std::uint32_t>(out, 2);
  appendLe<std::uint32_t>(out, std::uint32_t(12 + 8 + json.size() + 8 + bin.size()));
  appendLe<std::uint32_t>(out, std::uint32_t(json.size()));
  appendLe<std::uint32_t>(out, 0x4E4F534Au);  // "JSON"
  out.insert(out.end(), json.begin(), json.end());
  appendLe<std::uint32_t>(out, std::uint32_t(bin.size()));
  appendLe<std::uint32_t>(out, 0x004E4942u);  // "BIN\0"
  out.insert(out.end(), bin.begin(), bin.end());
  if (out.size() > 0xffffffffu)
    throw std::invalid_argument("mesh too large for one GLB file: " + path.string());
  writeBytes(out, path);
}

std::string toString(MeshFormat f) {
  constexpr core::NameTable<MeshFormat, 3> kNames{
      "mesh format",
      {{{MeshFormat::kObj, "obj"}, {MeshFormat::kPly, "ply"}, {MeshFormat::kGlb, "glb"}}}};
  return kNames.nameOf(f);
}

double coordinateRoundingBound(const terrain::Terrain& t, MeshFormat format) {
  if (format == MeshFormat::kObj) return std::sqrt(3.0) * 0.5e-4 * (1 + 1e-9);  // "%.4f"
  // Largest coordinate magnitude over the whole grid.
  const double hMax = std::max(std::abs(double(t.minHeight())), std::abs(double(t.maxHeight())));
  double bound;
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(&t.chart())) {
    bound = std::max({flat->dx() * t.grid().m(), flat->dy() * t.grid().m(), hMax});
  } else if (t.chart().radius() > 0 && t.chart().hasPoleRows()) {
    bound = t.chart().radius() + hMax;
  } else {
    bound = 0;
    for (int v = 0; v <= t.grid().m(); ++v) {
      for (int u = 0; u <= t.grid().m(); ++u)
        bound = std::max(bound, t.chart().position(u, v, t.height(u, v)).cwiseAbs().maxCoeff());
    }
  }
  // Round to nearest float: at most half an ulp, and an ulp at magnitude x is <= x * 2^-23.
  return std::sqrt(3.0) * bound * std::ldexp(1.0, -24) * (1 + 1e-6);
}

MeshExportReport exportMesh(const terrain::Terrain& t, double maxErrorM, MeshFormat format,
                            const std::filesystem::path& path, terrain::Mesh* meshOut) {
  MeshExportReport rep;
  rep.requestedErrorM = maxErrorM;
  rep.roundingM = coordinateRoundingBound(t, format);
  if (!std::isfinite(maxErrorM) || maxErrorM <= rep.roundingM) {
    char buf[256];
    std::snprintf(
        buf, sizeof buf,
        "--max-error %g m is not above the %.3g m by which %s coordinates of this planet can be "
        "rounded; ask for more",
        maxErrorM, rep.roundingM, toString(format).c_str());
    throw core::InputError(buf);
  }
  rep.meshedErrorM = maxErrorM - rep.roundingM;
  terrain::Mesh mesh = terrain::meshToError(t, rep.meshedErrorM);
  rep.vertices = mesh.gridIndex.size();
  rep.triangles = mesh.triangleCount();
  switch (format) {
    case MeshFormat::kObj:
      writeObj(t, mesh, path);
      break;
    case MeshFormat::kPly:
      writePly(t, mesh, path);
      break;
    case MeshFormat::kGlb: {
      const nlohmann::json extras = {
          {"planetsculpt",
           {{"chart", t.chart().name()},
            {"max_error_m", maxErrorM},
            {"units", "m"},
            {"frame", "planet frame rotated to +Y up: (x, y, z) -> (x, z, -y)"}}}};
      writeGlb(t, mesh, path, extras.dump());
      break;
    }
  }
  if (meshOut) *meshOut = std::move(mesh);
  return rep;
}

}  // namespace ps::io
