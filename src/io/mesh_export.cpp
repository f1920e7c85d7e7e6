#include "io/mesh_export.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <unordered_map>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "io/mesh_writers.hpp"
#include "terrain/error_mesher.hpp"

namespace ps::io {

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

MeshData meshData(const terrain::Terrain& t, const terrain::Mesh& mesh, bool withNormals,
                  std::string description) {
  MeshData out;
  out.positions.reserve(mesh.gridIndex.size());
  for (const auto gi : mesh.gridIndex) out.positions.push_back(gridPosition(t, gi));
  if (withNormals) out.normals = vertexNormals(t, mesh);
  out.indices = mesh.indices;
  out.description = std::move(description);
  return out;
}

}  // namespace

void writeObj(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
              const std::filesystem::path& path) {
  writeObjFile(
      meshData(terrain, mesh, false,
               "PlanetSculpt view mesh: " + std::to_string(mesh.gridIndex.size()) + " vertices, " +
                   std::to_string(mesh.triangleCount()) + " triangles, metres, planet frame"),
      path);
}

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
  writePlyFile(meshData(t, mesh, true, "PlanetSculpt mesh, metres, planet frame (z up)"), path);
}

void writeGlb(const terrain::Terrain& t, const terrain::Mesh& mesh,
              const std::filesystem::path& path, const std::string& extrasJson) {
  writeGlbFile(meshData(t, mesh, true, ""), path, extrasJson);
}

std::string toString(MeshFormat f) {
  constexpr core::NameTable<MeshFormat, 3> kNames{
      "mesh format",
      {{{MeshFormat::kObj, "obj"}, {MeshFormat::kPly, "ply"}, {MeshFormat::kGlb, "glb"}}}};
  return kNames.nameOf(f);
}

void writeMeshFile(const MeshData& mesh, MeshFormat format, const std::filesystem::path& path,
                   const std::string& extrasJson) {
  switch (format) {
    case MeshFormat::kObj:
      writeObjFile(mesh, path);
      break;
    case MeshFormat::kPly:
      writePlyFile(mesh, path);
      break;
    case MeshFormat::kGlb:
      writeGlbFile(mesh, path, extrasJson);
      break;
  }
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
