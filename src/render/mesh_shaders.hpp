#pragma once
// The planet mesh's shaders (render/planet_renderer.cpp). Two ways to shade a pixel:
//   * per pixel (the default): height, normal, tint and contour lines from the full-resolution
//     heights, sampled at the pixel's grid coordinates from the level of the height pyramid
//     where its footprint spans one to two texels (render/height_tile_cache.hpp: a tile cache
//     with a page table; where that level is not held, the nearest coarser one), so a coarse
//     mesh carries the silhouette and every pixel the relief;
//   * faceted: each triangle's own geometry (flat normals from screen-space derivatives, the
//     height interpolated across it), so the tessellation shows, as in paper 003's figures.
// The chart's frame comes per vertex (its up direction and the tangents along u and v, metres
// per grid step), so the shader knows no chart's formulas; only whether up points away from a
// centre (a sphere's). A seam the chart wraps is in the tiles' aprons.

#include <string>

namespace ps::render {

constexpr const char* kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 position;  // relative to the mesh's eye (planet frame)
layout(location = 1) in float height;   // metres above the reference surface
layout(location = 2) in vec2 gridUv;    // grid coordinates (u, v) of the vertex
layout(location = 3) in vec3 up;        // the chart's up direction there
layout(location = 4) in vec3 alongU;    // d position / d u (metres per grid step)
layout(location = 5) in vec3 alongV;    // d position / d v
uniform mat4 clipFromEyeRelative;       // projection * rotation * translate(meshEye - cameraEye)
uniform vec3 offset;                    // meshEye - cameraEye
out vec3 eyeRelative;                   // planet frame, relative to the camera
out float metres;
out vec2 grid;
out vec3 upDir, tangentU, tangentV;
void main() {
  eyeRelative = position + offset;
  metres = height;
  grid = gridUv;
  upDir = up;
  tangentU = alongU;
  tangentV = alongV;
  gl_Position = clipFromEyeRelative * vec4(position, 1.0);
}
)";

constexpr const char* kMeshFragment = R"(#version 330 core
in vec3 eyeRelative;
in float metres;
in vec2 grid;
in vec3 upDir, tangentU, tangentV;
uniform sampler1D ramp;       // hypsometric colours over [rampLow, rampHigh] metres
uniform float rampLow, rampHigh;
uniform vec3 sun;             // planet frame
uniform vec3 cameraPosition;  // planet frame (only for the outward direction)
uniform float contourInterval;  // 0: none
uniform int wireOnly;
uniform int perPixel;           // 1: shade from the height tiles
uniform sampler2DArray heightTiles;  // R32F tiles of the height pyramid, with a 1-texel apron
uniform usampler2D pageTable;         // mip level L: per tile of pyramid level L, its layer + 1
uniform float tileCells;              // cells per tile side
uniform int coarsestLevel;            // the pyramid's level of one tile
uniform float slotSide;               // texels per tile side (tileCells + 3)
uniform float reliefScale;      // vertical exaggeration of the shading (as the previews')
uniform int upKind;             // 0: each vertex's up; 1: a sphere about the origin; 2: a torus
                                // about z (tube centres at majorRadius); 3: a cylinder about z
uniform float majorRadius;      // the torus's
uniform int showTileLevels;     // 1: colour by the level read; red where it is coarser than asked
out vec4 colour;

// The outward direction of the reference surface at planet-frame point p (upKind 1-3; with 0,
// the direction from the origin, as for a sphere).
vec3 outwardAt(vec3 p) {
  if (upKind == 2) {
    float l = length(p.xy);
    return normalize(l > 0.0 ? p - vec3(p.xy * (majorRadius / l), 0.0) : p);
  }
  if (upKind == 3) return normalize(vec3(p.xy, 0.0));
  return normalize(p);
}

// The held tile for grid point g (level-0 grid coordinates) at `level` or the nearest coarser
// level: its layer, its corner in that level's texels, and 2^level.
void findTile(vec2 g, int level, out float layer, out vec2 corner, out float scale) {
  for (int l = level; l <= coarsestLevel; ++l) {
    scale = exp2(float(l));
    int last = (1 << (coarsestLevel - l)) - 1;
    ivec2 t = clamp(ivec2(floor(g / (scale * tileCells))), ivec2(0), ivec2(last));
    uint entry = texelFetch(pageTable, t, l).r;
    if (entry != 0u || l == coarsestLevel) {
      layer = float(entry) - 1.0;
      corner = vec2(t) * tileCells;
      return;
    }
  }
}

// The height at `local` (texels of the tile's level from its corner; the apron holds -1 and
// tileCells + 1), bilinear.
float tileHeight(vec2 local, float layer) {
  return texture(heightTiles, vec3((local + 1.5) / slotSide, layer)).r;
}

void main() {
  if (wireOnly == 1) { colour = vec4(0.08, 0.08, 0.08, 1.0); return; }
  vec3 n;
  float h;
  if (perPixel == 1) {
    // The level where the pixel's footprint spans one to two texels (as a mip level would be
    // chosen); there the slope is taken over one texel and the height as the mean of two
    // samples across the footprint, so the picture stays still as the mesh changes.
    vec2 footprint = fwidth(grid);
    float widest = max(footprint.x, footprint.y);
    int level = clamp(int(floor(log2(max(widest, 1.0)))), 0, coarsestLevel);
    float layer, scale;
    vec2 corner;
    findTile(grid, level, layer, corner, scale);
    if (showTileLevels == 1) {
      float shade = 1.0 - float(level) / float(coarsestLevel + 1);
      colour = scale > exp2(float(level)) ? vec4(1.0, 0.0, 0.0, 1.0) : vec4(0.0, shade, 1.0 - shade, 1.0);
      return;
    }
    vec2 local = grid / scale - corner;
    float h0 = tileHeight(local, layer);
    h = widest > 2.0 ? 0.5 * (h0 + tileHeight(local + min(0.5 * footprint / scale, vec2(1.0)), layer))
                     : h0;
    // Differences on the grid (one texel of the level forward, for a normal half a texel off),
    // per grid step, turned into the surface gradient with the chart's tangents (orthogonal on
    // every chart here); where a tangent vanishes (a pole) its term does too.
    float dhu = (tileHeight(local + vec2(1.0, 0.0), layer) - h0) / scale;
    float dhv = (tileHeight(local + vec2(0.0, 1.0), layer) - h0) / scale;
    float uu = dot(tangentU, tangentU), vv = dot(tangentV, tangentV);
    vec3 gradient = (uu > 1e-6 ? dhu / uu * tangentU : vec3(0.0)) +
                    (vv > 1e-6 ? dhv / vv * tangentV : vec3(0.0));
    // A sphere's, a torus's or a cylinder's up from the pixel's own position: interpolating the
    // vertices' up across a coarse triangle would bend the light at its edges (Mach bands along
    // the mesh).
    vec3 u = upKind != 0 ? outwardAt(eyeRelative + cameraPosition) : normalize(upDir);
    n = normalize(u - reliefScale * (gradient - dot(gradient, u) * u));
  } else {
    h = metres;
    // Flat normals from screen-space derivatives: the facets of the tessellation show, as in
    // paper 003's figures.
    n = normalize(cross(dFdx(eyeRelative), dFdy(eyeRelative)));
    if (dot(n, outwardAt(eyeRelative + cameraPosition)) < 0.0) n = -n;
  }
  float light = 0.3 + 0.7 * max(dot(n, sun), 0.0);
  vec3 c = texture(ramp, clamp((h - rampLow) / (rampHigh - rampLow), 0.0, 1.0)).rgb;
  c *= light;
  if (contourInterval > 0.0) {
    float x = h / contourInterval;
    float d = abs(fract(x - 0.5) - 0.5) / max(fwidth(x), 1e-6);
    c = mix(vec3(0.05), c, clamp(d - 0.5, 0.0, 1.0) * 0.6 + 0.4);
  }
  colour = vec4(c, 1.0);
}
)";

// A spliced patch's triangles (terrain/mesh_patch) are shaded from their own heights and
// geometry, not the grid's tiles: kMeshFragment with this branch put in front of its per-pixel
// one, in a program of its own, so that the view's program is compiled from the very source
// it always was: a mesh without a patch draws the same bits as before, whatever a compiler
// makes of the extra branch.
constexpr const char* kOwnSurfaceBranch = R"(  if (perPixel == 1) {
    // A patch (the sand TIN's region) is linear on each triangle: its height is the
    // interpolated one, and its slope is how that height changes across the facet. From
    // screen-space derivatives, g is the height's gradient within the facet; a surface of
    // horizontal gradient G has g = (G + |G|^2 up) / (1 + |G|^2), so G = g_h / (1 - g . up),
    // lit with the same exaggeration as the grid's gradient below (the chord's tilt against
    // the pixel's up, L / 2R on a triangle of side L, enters only to second order).
    h = metres;
    vec3 a = dFdx(eyeRelative), b = dFdy(eyeRelative);
    float ha = dFdx(metres), hb = dFdy(metres);
    float aa = dot(a, a), ab = dot(a, b), bb = dot(b, b);
    float det = aa * bb - ab * ab;
    vec3 g = det > 0.0 ? ((bb * ha - ab * hb) * a + (aa * hb - ab * ha) * b) / det : vec3(0.0);
    vec3 u = upKind != 0 ? outwardAt(eyeRelative + cameraPosition) : normalize(upDir);
    float along = dot(g, u);
    vec3 G = (g - along * u) / max(1.0 - along, 1e-3);
    n = normalize(u - reliefScale * G);
  } else
)";

inline std::string ownSurfaceFragment() {
  std::string s = kMeshFragment;
  const std::string at = "  if (perPixel == 1) {";
  return s.insert(s.find(at), kOwnSurfaceBranch);
}

}  // namespace ps::render
