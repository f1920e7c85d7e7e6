#include "io/mesh_export.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <unordered_map>

#include "core/chart_factory.hpp"
#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "io/mesh_writers.hpp"
#include "terrain/error_mesher.hpp"

namespace ps::io {

terrain::Mesh weldMesh(const terrain::Terrain& t, const terrain::Mesh& mesh) {
  terrain::Mesh out;
  out.eye = mesh.eye;
  out.generation = terrain::nextMeshGeneration();
  const auto side = std::uint64_t(t.grid().side());
  std::unordered_map<std::uint64_t, std::uint32_t> welded;  // canonical grid index -> vertex
  welded.reserve(mesh.gridIndex.size());
  std::vector<std::uint32_t> vertexOf(mesh.gridIndex.size());
  for (std::size_t i = 0; i < mesh.gridIndex.size(); ++i) {
    const std::uint64_t gi = mesh.gridIndex[i];
    const core::GridPoint p = t.chart().canonical(int(gi % side), int(gi / side));
    const std::uint64_t key = std::uint64_t(p.v) * side + std::uint64_t(p.u);
    const auto [it, fresh] = welded.try_emplace(key, std::uint32_t(out.gridIndex.size()));
    if (fresh) {
      out.gridIndex.push_back(key);
      out.positions.push_back(
          (t.chart().position(p.u, p.v, t.height(p.u, p.v)) - mesh.eye).cast<float>());
    }
    vertexOf[i] = it->second;
  }
  out.indices.reserve(mesh.indices.size());
  for (std::size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
    const std::uint32_t a = vertexOf[mesh.indices[k]], b = vertexOf[mesh.indices[k + 1]],
                        c = vertexOf[mesh.indices[k + 2]];
    if (a == b || b == c || c == a) continue;  // two vertices of one pole row: no area
    out.indices.insert(out.indices.end(), {a, b, c});
  }
  return out;
}

MeshData weldedMeshData(const terrain::Terrain& t, const terrain::Mesh& mesh, bool withNormals,
                        std::string description) {
  const terrain::Mesh welded = weldMesh(t, mesh);
  MeshData out;
  const auto side = std::uint64_t(t.grid().side());
  out.positions.reserve(welded.gridIndex.size());
  for (const std::uint64_t gi : welded.gridIndex) {
    const int u = int(gi % side), v = int(gi / side);
    out.positions.push_back(t.chart().position(u, v, t.height(u, v)));
  }
  out.indices = welded.indices;
  if (withNormals) out.normals = areaWeightedNormals(out);
  out.description = std::move(description);
  return out;
}

void writeObj(const terrain::Terrain& terrain, const terrain::Mesh& mesh,
              const std::filesystem::path& path) {
  MeshData data = weldedMeshData(terrain, mesh, false, "");
  data.description = "PlanetSculpt view mesh: " + std::to_string(data.positions.size()) +
                     " vertices, " + std::to_string(data.indices.size() / 3) +
                     " triangles, metres, planet frame";
  writeObjFile(data, path);
}

void writePly(const terrain::Terrain& t, const terrain::Mesh& mesh,
              const std::filesystem::path& path) {
  writePlyFile(weldedMeshData(t, mesh, true, "PlanetSculpt mesh, metres, planet frame (z up)"),
               path);
}

void writeGlb(const terrain::Terrain& t, const terrain::Mesh& mesh,
              const std::filesystem::path& path, const std::string& extrasJson) {
  writeGlbFile(weldedMeshData(t, mesh, true, ""), path, extrasJson);
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
  } else if (core::isSphere(core::shapeOf(t.chart()))) {
    bound = t.chart().sphereRadius() + hMax;
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
  // Counted as written: welded by the chart's topology (the pole rows' triangles of no area gone).
  const MeshData data = weldedMeshData(
      t, mesh, format != MeshFormat::kObj,
      format == MeshFormat::kObj
          ? "PlanetSculpt mesh to " + std::to_string(maxErrorM) + " m, metres, planet frame"
          : "PlanetSculpt mesh, metres, planet frame (z up)");
  rep.vertices = data.positions.size();
  rep.triangles = data.indices.size() / 3;
  const nlohmann::json extras = {
      {"planetsculpt",
       {{"chart", t.chart().name()},
        {"max_error_m", maxErrorM},
        {"units", "m"},
        {"frame", "planet frame rotated to +Y up: (x, y, z) -> (x, z, -y)"}}}};
  writeMeshFile(data, format, path, format == MeshFormat::kGlb ? extras.dump() : "{}");
  if (meshOut) *meshOut = std::move(mesh);
  return rep;
}

}  // namespace ps::io
