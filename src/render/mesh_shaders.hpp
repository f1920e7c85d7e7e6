#pragma once
// The planet mesh's shaders (render/planet_renderer.cpp). Two ways to shade a pixel:
//   * per pixel (the default): height, normal, tint and contour lines from the full-resolution
//     heights in a texture (render/height_texture.hpp), sampled at the pixel's grid coordinates,
//     so a coarse mesh carries the silhouette and every pixel the relief;
//   * faceted: each triangle's own geometry (flat normals from screen-space derivatives, the
//     height interpolated across it), so the tessellation shows, as in paper 003's figures.
// The chart's frame comes per vertex (its up direction and the tangents along u and v, metres
// per grid step), so the shader knows no chart's formulas; only whether u wraps and whether up
// points away from a centre (a sphere's).

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
uniform int perPixel;           // 1: shade from the height texture
uniform sampler2D heights;      // R32F, texel (u, v) = grid vertex (u, v)
uniform float gridM;            // the grid's last index m (side - 1)
uniform int wrapsU;             // columns 0 and m are one (a seam)
uniform float reliefScale;      // vertical exaggeration of the shading (as the previews')
uniform int radialUp;           // up is the direction from the planet's centre (a sphere)
out vec4 colour;

float heightAt(vec2 g) {
  if (wrapsU == 1) g.x = mod(g.x, gridM);
  return texture(heights, (g + 0.5) / (gridM + 1.0)).r;
}

void main() {
  if (wireOnly == 1) { colour = vec4(0.08, 0.08, 0.08, 1.0); return; }
  vec3 n;
  float h;
  if (perPixel == 1) {
    // Where a pixel spans many texels (a small planet far away), one sample per pixel would
    // pick texels at random: the slope is taken over the pixel's footprint and the height is
    // the mean of two samples across it, so the picture stays still as the mesh changes (at
    // four fetches a pixel, one more than a magnified texture needs).
    vec2 footprint = fwidth(grid);
    float step = max(1.0, 0.5 * max(footprint.x, footprint.y));
    float h0 = heightAt(grid);
    h = step > 1.0 ? 0.5 * (h0 + heightAt(grid + 0.5 * footprint)) : h0;
    // Differences on the grid (one step forward, for a normal half a step off), turned into the
    // surface gradient with the chart's tangents (orthogonal on every chart here); where a
    // tangent vanishes (a pole) its term does too.
    float dhu = (heightAt(grid + vec2(step, 0.0)) - h0) / step;
    float dhv = (heightAt(grid + vec2(0.0, step)) - h0) / step;
    float uu = dot(tangentU, tangentU), vv = dot(tangentV, tangentV);
    vec3 gradient = (uu > 1e-6 ? dhu / uu * tangentU : vec3(0.0)) +
                    (vv > 1e-6 ? dhv / vv * tangentV : vec3(0.0));
    // A sphere's up from the pixel's own position: interpolating the vertices' up across a
    // coarse triangle would bend the light at its edges (Mach bands along the mesh).
    vec3 u = radialUp == 1 ? normalize(eyeRelative + cameraPosition) : normalize(upDir);
    n = normalize(u - reliefScale * (gradient - dot(gradient, u) * u));
  } else {
    h = metres;
    // Flat normals from screen-space derivatives: the facets of the tessellation show, as in
    // paper 003's figures.
    n = normalize(cross(dFdx(eyeRelative), dFdy(eyeRelative)));
    if (dot(n, normalize(eyeRelative + cameraPosition)) < 0.0) n = -n;
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

}  // namespace ps::render
