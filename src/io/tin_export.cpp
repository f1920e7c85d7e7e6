#include "io/tin_export.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/flat_chart.hpp"
#include "core/input_error.hpp"
#include "io/height_image.hpp"
#include "io/mesh_writers.hpp"
#include "tin/tin_check.hpp"
#include "tin/tin_mesher.hpp"

namespace ps::io {

namespace {

using core::exactNumber;

// The control map's value in [0, 1] per lattice sample (rows flipped: image row 0 is j = H-1).
// `terrainGeo`: the heightmap's georeferencing, which a georeferenced control map must share;
// `planet`: a planet's control map, which may only be georeferenced in degrees.
std::vector<float> readControlMap(const std::filesystem::path& path, int width, int height,
                                  const std::optional<GeoReference>& terrainGeo, bool planet) {
  const HeightImage img = readHeightImage(path);
  const std::string name = path.string();
  if (img.geo && planet && !img.geo->geographic)
    throw core::InputError(name +
                           ": the control map is georeferenced in a projected system; a "
                           "planet's control map is in latitude and longitude");
  if (img.geo && terrainGeo) {
    const GeoReference &a = *img.geo, &b = *terrainGeo;
    auto near = [](double x, double y) {
      return std::abs(x - y) <= 1e-9 * std::max({1.0, std::abs(x), std::abs(y)});
    };
    if (a.geographic != b.geographic || !near(a.pixelScaleX, b.pixelScaleX) ||
        !near(a.pixelScaleY, b.pixelScaleY) || !near(a.originX, b.originX) ||
        !near(a.originY, b.originY))
      throw core::InputError(
          name + ": the control map's georeferencing (origin " + exactNumber(a.originX) + ", " +
          exactNumber(a.originY) + ", pixel " + exactNumber(a.pixelScaleX) + " x " +
          exactNumber(a.pixelScaleY) + (a.geographic ? " degrees" : "") +
          ") is not the heightmap's (origin " + exactNumber(b.originX) + ", " +
          exactNumber(b.originY) + ", pixel " + exactNumber(b.pixelScaleX) + " x " +
          exactNumber(b.pixelScaleY) + (b.geographic ? " degrees" : "") + ")");
  }
  if (img.width != width || img.height != height)
    throw core::InputError(name + ": the control map is " + std::to_string(img.width) + "x" +
                           std::to_string(img.height) + " pixels; it must match the " +
                           std::to_string(width) + "x" + std::to_string(height) +
                           " samples being meshed, pixel for pixel");
  double full = 1.0;  // the value that means "white"
  if (img.kind.rfind("8-bit", 0) == 0) full = 255.0;
  if (img.kind.rfind("16-bit", 0) == 0) full = 65535.0;
  std::vector<float> out(img.values.size());
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const double c = img.at(i, height - 1 - j) / full;
      if (!(c >= 0 && c <= 1))
        throw core::InputError(name + ": control map value " +
                               exactNumber(img.at(i, height - 1 - j)) + " at pixel (" +
                               std::to_string(i) + ", " + std::to_string(height - 1 - j) +
                               ") is outside 0.." + exactNumber(full) + " (" + img.kind + ")");
      out[std::size_t(j) * std::size_t(width) + std::size_t(i)] = float(c);
    }
  }
  return out;
}

void validateOptions(const TinExportOptions& o) {
  if (!(std::isfinite(o.maxErrorM) && o.maxErrorM > 0))
    throw core::InputError("--max-error " + exactNumber(o.maxErrorM) +
                           " m: a TIN needs an error above 0");
  if (o.controlMap.has_value() != o.controlErrorM.has_value())
    throw core::InputError(
        "--control-map and --control-error go together (the map says where, "
        "the error how close)");
  if (o.controlErrorM && !(std::isfinite(*o.controlErrorM) && *o.controlErrorM > 0))
    throw core::InputError("--control-error " + exactNumber(*o.controlErrorM) +
                           " m must be above 0");
  if (!(std::isfinite(o.minAreaM2) && o.minAreaM2 >= 0))
    throw core::InputError("--min-area " + exactNumber(o.minAreaM2) + " m^2 must be 0 or more");
}

double roundCoordinate(double x, MeshFormat f) {
  return f == MeshFormat::kObj ? std::round(x * 1e4) / 1e4 : double(float(x));
}

// A bound on how far the format's rounding moves any vertex (as the bintree export's).
double roundingBound(double maxCoordinate, MeshFormat f) {
  if (f == MeshFormat::kObj) return std::sqrt(3.0) * 0.5e-4 * (1 + 1e-9);
  return std::sqrt(3.0) * maxCoordinate * std::ldexp(1.0, -24) * (1 + 1e-6);
}

using Clock = std::chrono::steady_clock;

// Builds the TIN at tolerances shrunk by the coordinate rounding, measures the written mesh
// against the requested tolerances on every sample, and shrinks further if the rounding took
// any sample over (at most three tries; then it says so).
nlohmann::json meshAndWrite(tin::SampleField field, const std::filesystem::path& out,
                            MeshFormat format, const TinExportOptions& o, double latticeAreaM2,
                            double maxCoordinate,
                            const std::optional<GeoReference>& terrainGeo = std::nullopt) {
  validateOptions(o);
  std::vector<float> requested;  // per-sample tolerances when there is a control map
  if (o.controlMap) {
    requested = readControlMap(*o.controlMap, field.width, field.height, terrainGeo,
                               field.metric == tin::ErrorMetric::kChart3d);
    for (float& c : requested)
      c = float(o.maxErrorM + double(c) * (*o.controlErrorM - o.maxErrorM));
  }
  const double smallest = o.controlErrorM ? std::min(o.maxErrorM, *o.controlErrorM) : o.maxErrorM;
  const double rounding = roundingBound(maxCoordinate, format);
  tin::TinOptions topt;
  topt.minAngleDeg = o.minAngleDeg;
  topt.minArea = o.minAreaM2 / latticeAreaM2;

  double shrink = rounding;
  std::vector<float> shrunk;
  tin::Tin tin;
  tin::TinReport rep;
  tin::TinErrorCheck check;
  std::vector<Eigen::Vector3d> positions, written;
  tin::WeldedMesh welded;
  double checkMs = 0;
  for (int attempt = 0;; ++attempt) {
    if (shrink >= smallest)
      throw core::InputError("--max-error " + exactNumber(smallest) + " m is not above the " +
                             exactNumber(shrink) + " m by which " + toString(format) +
                             " coordinates of this terrain can be rounded; ask for more");
    if (requested.empty()) {
      field.uniformTolerance = o.maxErrorM - shrink;
    } else {
      shrunk.resize(requested.size());
      for (std::size_t k = 0; k < requested.size(); ++k) shrunk[k] = float(requested[k] - shrink);
      field.perSampleTolerance = shrunk;
    }
    tin = tin::buildTin(field, topt, &rep);

    welded = tin::weldTin(field, tin);
    positions.assign(welded.vertices, Eigen::Vector3d::Zero());
    std::vector<bool> placed(welded.vertices, false);
    written.resize(tin.xy.size());
    for (std::size_t v = 0; v < tin.xy.size(); ++v) {
      const std::uint32_t w = welded.vertexOf[v];
      if (!placed[w]) {
        positions[w] = field.positionAt(tin.xy[v].x(), tin.xy[v].y(), tin.h[v]);
        for (int k = 0; k < 3; ++k) positions[w][k] = roundCoordinate(positions[w][k], format);
        placed[w] = true;
      }
      written[v] = positions[w];
    }
    const auto t0 = Clock::now();
    tin::SampleField asRequested = field;
    asRequested.uniformTolerance = o.maxErrorM;
    asRequested.perSampleTolerance = requested;
    check = tin::measureTinError(asRequested, tin, written);
    checkMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (check.uncovered > 0)
      throw std::logic_error("TIN export: " + std::to_string(check.uncovered) +
                             " samples fell outside every triangle");
    if (check.maxRatio <= 1.0) break;
    if (attempt == 2)
      throw std::runtime_error("TIN export: after rounding, a sample is " +
                               exactNumber(check.maxRatio) + " times its allowed error");
    shrink += (check.maxRatio - 1.0) * smallest + rounding;
  }

  MeshData mesh;
  mesh.positions = positions;
  mesh.indices.reserve(welded.triangles.size() * 3);
  for (const auto& t : welded.triangles)
    mesh.indices.insert(mesh.indices.end(), t.begin(), t.end());
  const bool quality = o.minAngleDeg > 0;
  mesh.description = "PlanetSculpt TIN (" + std::string(quality ? "quality" : "fewest triangles") +
                     "): " + std::to_string(welded.vertices) + " vertices, " +
                     std::to_string(welded.triangles.size()) + " triangles, metres";
  nlohmann::json summary = {{"tin", true},
                            {"mode", quality ? "quality" : "fewest"},
                            {"max_error_m", o.maxErrorM},
                            {"coordinate_rounding_m", rounding},
                            {"meshed_at_error_m", o.maxErrorM - shrink},
                            {"measured_error_m", check.maxError},
                            {"measured_error_ratio", check.maxRatio},
                            {"samples_checked", check.samples},
                            {"vertices", welded.vertices},
                            {"triangles", welded.triangles.size()},
                            {"greedy_vertices", rep.greedyVertices},
                            {"steiner_vertices", rep.steinerVertices},
                            {"smallest_angle_deg", rep.smallestAngleDeg},
                            {"greedy_ms", rep.greedyMs},
                            {"refine_ms", rep.refineMs},
                            {"check_ms", checkMs}};
  if (quality) {
    summary["min_angle_deg"] = o.minAngleDeg;
    summary["angle_met"] = rep.angleMet;
    summary["angle_budget_exhausted"] = rep.budgetExhausted;
    summary["angle_guaranteed_up_to_deg"] = tin::kGuaranteedAngleDeg;
  }
  if (o.controlErrorM) summary["control_error_m"] = *o.controlErrorM;
  if (welded.collapsed) summary["pole_triangles_welded_away"] = welded.collapsed;
  writeMeshFile(mesh, format, out,
                nlohmann::json({{"planetsculpt", {{"tin", summary}, {"units", "m"}}}}).dump());
  return summary;
}

}  // namespace

tin::SampleField terrainSampleField(const terrain::Terrain& t) {
  tin::SampleField field;
  field.width = field.height = t.grid().side();
  field.heights = t.heights();
  if (const auto* flat = dynamic_cast<const core::FlatChart*>(&t.chart())) {
    field.metric = tin::ErrorMetric::kVertical;
    field.dx = flat->dx();
    field.dy = flat->dy();
  } else {
    field.metric = tin::ErrorMetric::kChart3d;
    field.chart = &t.chart();
  }
  return field;
}

tin::SampleField heightSampleField(const HeightSamples& s) {
  tin::SampleField field;
  field.width = s.width;
  field.height = s.height;
  field.heights = s.heights;
  field.metric = tin::ErrorMetric::kVertical;
  field.dx = s.dx;
  field.dy = s.dy;
  return field;
}

namespace {

// The window of a lat-long grid covering a region given in degrees, its heights copied.
std::vector<float> regionWindow(const terrain::Terrain& t, const std::array<double, 4>& r,
                                tin::SampleField& field) {
  const double south = r[0], west = r[1], north = r[2], east = r[3];
  if (!(t.chart().hasPoleRows() && t.chart().wrapsU()))
    throw core::InputError("--region is in latitude and longitude: it needs a lat-long planet");
  if (!(south >= -90 && north <= 90 && south < north && west >= -180 && east <= 180 && west < east))
    throw core::InputError("--region " + exactNumber(south) + "," + exactNumber(west) + "," +
                           exactNumber(north) + "," + exactNumber(east) +
                           ": give SOUTH,WEST,NORTH,EAST in degrees, south < north, west < east "
                           "(a region across the +-180 meridian is not supported)");
  const int m = t.grid().m();
  const int i0 = std::clamp(int(std::floor((west + 180) / 360 * m)), 0, m);
  const int i1 = std::clamp(int(std::ceil((east + 180) / 360 * m)), 0, m);
  const int j0 = std::clamp(int(std::floor((south + 90) / 180 * m)), 0, m);
  const int j1 = std::clamp(int(std::ceil((north + 90) / 180 * m)), 0, m);
  if (i1 - i0 < 1 || j1 - j0 < 1)
    throw core::InputError("--region is smaller than one cell of the planet's grid");
  field.i0 = i0;
  field.j0 = j0;
  field.width = i1 - i0 + 1;
  field.height = j1 - j0 + 1;
  std::vector<float> heights(std::size_t(field.width) * std::size_t(field.height));
  for (int j = 0; j < field.height; ++j)
    for (int i = 0; i < field.width; ++i)
      heights[std::size_t(j) * std::size_t(field.width) + std::size_t(i)] =
          t.height(i + i0, j + j0);
  return heights;
}

}  // namespace

nlohmann::json exportTerrainTin(const terrain::Terrain& t, const std::filesystem::path& out,
                                MeshFormat format, const TinExportOptions& o) {
  tin::SampleField field = terrainSampleField(t);
  std::vector<float> window;
  if (o.regionDeg) {
    window = regionWindow(t, *o.regionDeg, field);
    field.heights = window;
  }
  const int m = t.grid().m();
  const double hMax = std::max(std::abs(double(t.minHeight())), std::abs(double(t.maxHeight())));
  double area, maxCoordinate;
  if (field.metric == tin::ErrorMetric::kVertical) {
    area = field.dx * field.dy;
    maxCoordinate = std::max({field.dx * m, field.dy * m, hMax});
  } else if (const double r = t.chart().sphereRadius(); r > 0) {
    // A lattice cell's area at the equator, where cells are largest.
    area = (2 * std::numbers::pi * r / m) * (std::numbers::pi * r / m);
    maxCoordinate = r + hMax;
  } else {
    // No sphere (the torus, the cylinder): the largest cell and coordinate of a coarse
    // lattice of the grid at height 0.
    area = 0, maxCoordinate = 0;
    const int step = std::max(1, m / 32);
    for (int v = 0; v + 1 <= m; v += step)
      for (int u = 0; u + 1 <= m; u += step) {
        const Eigen::Vector3d p = t.chart().position(u, v, 0.0);
        area = std::max(area, (t.chart().position(u + 1, v, 0.0) - p).norm() *
                                  (t.chart().position(u, v + 1, 0.0) - p).norm());
        maxCoordinate = std::max(maxCoordinate, p.norm());
      }
    maxCoordinate += hMax;
  }
  nlohmann::json summary = meshAndWrite(field, out, format, o, area, maxCoordinate);
  summary["error_metric"] = field.metric == tin::ErrorMetric::kVertical ? "vertical" : "3d";
  if (o.regionDeg) summary["region_grid_window"] = {field.i0, field.j0, field.width, field.height};
  return summary;
}

nlohmann::json exportSamplesTin(const HeightSamples& s, const std::filesystem::path& out,
                                MeshFormat format, const TinExportOptions& o) {
  if (o.regionDeg) throw core::InputError("--region applies to planets (lat-long charts)");
  double hMax = 0;
  for (const float h : s.heights) hMax = std::max(hMax, double(std::abs(h)));
  const double maxCoordinate = std::max({s.dx * (s.width - 1), s.dy * (s.height - 1), hMax});
  nlohmann::json summary =
      meshAndWrite(heightSampleField(s), out, format, o, s.dx * s.dy, maxCoordinate, s.geo);
  summary["error_metric"] = "vertical";
  summary["samples"] = {s.width, s.height};
  summary["spacing_m"] = {s.dx, s.dy};
  return summary;
}

}  // namespace ps::io
