#include "io/mesh_writers.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "io/atomic_file.hpp"

namespace ps::io {

namespace {

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

const std::vector<Eigen::Vector3f>& normalsOf(const MeshData& mesh,
                                              std::vector<Eigen::Vector3f>& scratch) {
  if (mesh.normals.size() == mesh.positions.size()) return mesh.normals;
  scratch = areaWeightedNormals(mesh);
  return scratch;
}

}  // namespace

std::vector<Eigen::Vector3f> areaWeightedNormals(const MeshData& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.positions.size(), Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
    const auto a = mesh.indices[k], b = mesh.indices[k + 1], c = mesh.indices[k + 2];
    const Eigen::Vector3d n =
        (mesh.positions[b] - mesh.positions[a]).cross(mesh.positions[c] - mesh.positions[a]);
    sum[a] += n, sum[b] += n, sum[c] += n;
  }
  std::vector<Eigen::Vector3f> out(sum.size());
  for (std::size_t i = 0; i < sum.size(); ++i)
    out[i] = sum[i].norm() > 0 ? Eigen::Vector3f(sum[i].normalized().cast<float>())
                               : Eigen::Vector3f::UnitZ();
  return out;
}

void writeObjFile(const MeshData& mesh, const std::filesystem::path& path) {
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp);
    if (!mesh.description.empty()) f << "# " << mesh.description << "\n";
    char line[128];
    for (const Eigen::Vector3d& p : mesh.positions) {
      std::snprintf(line, sizeof line, "v %.4f %.4f %.4f\n", p.x(), p.y(), p.z());
      f << line;
    }
    const bool grouped = mesh.triangleGroup.size() * 3 == mesh.indices.size();
    const std::size_t groups = grouped ? mesh.groupNames.size() : 1;
    for (std::size_t g = 0; g < groups; ++g) {
      if (grouped) f << "g " << mesh.groupNames[g] << '\n';
      for (std::size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
        if (grouped && mesh.triangleGroup[k / 3] != g) continue;
        f << "f " << mesh.indices[k] + 1 << ' ' << mesh.indices[k + 1] + 1 << ' '
          << mesh.indices[k + 2] + 1 << '\n';
      }
    }
    if (!f) throw std::runtime_error("cannot write " + path.string());
  });
}

void writePlyFile(const MeshData& mesh, const std::filesystem::path& path) {
  std::vector<Eigen::Vector3f> scratch;
  const auto& normals = normalsOf(mesh, scratch);
  const std::size_t nv = mesh.positions.size(), nt = mesh.indices.size() / 3;
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  if (!mesh.description.empty()) header += "comment " + mesh.description + "\n";
  header += "element vertex " + std::to_string(nv) + "\n";
  for (const char* p : {"x", "y", "z", "nx", "ny", "nz"})
    header += std::string("property float ") + p + "\n";
  header += "element face " + std::to_string(nt) + "\n";
  header += "property list uchar int vertex_indices\nend_header\n";
  std::vector<unsigned char> out(header.begin(), header.end());
  out.reserve(out.size() + nv * 24 + nt * 13);
  for (std::size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3f p = mesh.positions[i].cast<float>();
    for (int k = 0; k < 3; ++k) appendLe<float>(out, p[k]);
    for (int k = 0; k < 3; ++k) appendLe<float>(out, normals[i][k]);
  }
  for (std::size_t k = 0; k < nt; ++k) {
    out.push_back(3);
    for (std::size_t j = 0; j < 3; ++j)
      appendLe<std::int32_t>(out, std::int32_t(mesh.indices[3 * k + j]));
  }
  writeBytes(out, path);
}

void writeGlbFile(const MeshData& mesh, const std::filesystem::path& path,
                  const std::string& extrasJson) {
  const std::size_t nv = mesh.positions.size(), ni = mesh.indices.size();
  if (nv == 0 || ni == 0)
    throw std::invalid_argument("cannot write an empty mesh to " + path.string());
  std::vector<Eigen::Vector3f> scratch;
  const auto& normals = normalsOf(mesh, scratch);
  std::vector<unsigned char> bin;
  bin.reserve(nv * 24 + ni * 4);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY),
                  hi = Eigen::Vector3f::Constant(-INFINITY);
  for (const Eigen::Vector3d& p : mesh.positions) {
    const Eigen::Vector3f q(float(p.x()), float(p.z()), float(-p.y()));  // +Y up
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
    for (int k = 0; k < 3; ++k) appendLe<float>(bin, q[k]);
  }
  for (const Eigen::Vector3f& n : normals) {
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

}  // namespace ps::io
