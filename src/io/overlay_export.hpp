#pragma once
// `planetsculpt overlay TERRAIN ROAD.obj --mode stitch|stencil --error E --out FILE`: a road
// mesh placed on a planet or a flat heightmap, stitched or stenciled into the terrain's TIN
// (tin/overlay.hpp), written as OBJ (groups "terrain" and "road"), PLY or GLB.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/export.hpp"
#include "io/heightmap_import.hpp"
#include "io/obj_triangles.hpp"
#include "io/road_placement.hpp"
#include "tin/overlay.hpp"

namespace ps::io {

struct OverlayOptions {
  tin::OverlayMode mode = tin::OverlayMode::kStitch;
  double errorM = 0;  // the terrain TIN's error, which the stencil's re-meshing and a planet
                      // road's edges (how far they may stray from the surface's paths) keep too
  // Planets (required): where the road's origin lies (io/road_placement.hpp: LAT,LON on a
  // sphere, AROUND,ACROSS on a torus, AROUND,ALONG on a cylinder) and the heading of its +y axis
  // (degrees clockwise from north). Flat terrains (optional): the origin in the terrain's metres
  // (x east, y north) and the heading; default 0, 0, 0.
  std::optional<std::array<double, 3>> at = {};
  // A stitch on a sphere goes in the road's own plane (tin/plane_stitch.hpp) unless this asks for
  // the chart's grid (tin/overlay.hpp; as before 2026-12-08, for comparison).
  bool stitchInGrid = false;
};

// The road's vertices (x, y: metres in its own frame; z: height in metres above the terrain's
// datum) in the terrain's lattice coordinates; on a planet laid by io/road_placement.hpp, a road
// across a glued side of the chart's grid in one copy for each side it reaches. Throws
// core::InputError for a placement the grid cannot hold (a road wrapped round the end of an
// octahedral fold, one that folds over on a tube or turns over by a lat-long pole).
LaidRoad placeRoad(const ObjTriangles& road, const tin::SampleField& field,
                   const OverlayOptions& options, const std::string& name);

nlohmann::json overlayFromFiles(const std::filesystem::path& terrain,
                                const ImportOptions& heightmapOptions,
                                const std::filesystem::path& road, const std::filesystem::path& out,
                                ExportFormat format, const OverlayOptions& options,
                                std::vector<std::string>& notes);

}  // namespace ps::io
