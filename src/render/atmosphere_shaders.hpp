#pragma once
// Shaders of the AR view's board shadow and atmosphere rim (render/atmosphere_passes.hpp), in
// units of the planet's radius R around its centre, so float keeps its precision at any scale.

namespace ps::render {

// The board shadow: a quad on the board plane, positions relative to the camera eye (float, as
// the mesh's) and the same points relative to the planet's centre / R.
inline constexpr const char* kBoardShadowVertex = R"(#version 330 core
layout(location = 0) in vec3 position;  // eye-relative, planet frame (planet metres)
layout(location = 1) in vec3 board;     // relative to the planet's centre, / R
uniform mat4 clipFromEyeRelative;
out vec3 q;
void main() {
  q = board;
  gl_Position = clipFromEyeRelative * vec4(position, 1.0);
}
)";

// d: the distance (/ R) from the planet's centre to the ray q + t * sun (t > 0); full shadow
// inside `inner`, none beyond `outer`, faded out far from the contact point `foot`. Drawn with
// glBlendFunc(GL_ZERO, GL_SRC_COLOR): the video is multiplied by 1 - strength * shadow.
inline constexpr const char* kBoardShadowFragment = R"(#version 330 core
in vec3 q;
uniform vec3 sun;   // unit, toward the sun
uniform vec3 foot;  // where the planet touches the board, / R
uniform float inner, outer, strength, fadeStart, fadeEnd;
out vec4 colour;
void main() {
  float t = -dot(q, sun);  // along the ray to the point closest to the centre
  float shadow = 0.0;
  if (t > 0.0) {
    float d = length(q + t * sun);
    shadow = 1.0 - smoothstep(inner, outer, d);
    shadow *= 1.0 - smoothstep(fadeStart, fadeEnd, length(q - foot));
  }
  colour = vec4(vec3(1.0 - strength * shadow), 1.0);
}
)";

// The atmosphere rim: a square through the planet's centre, facing the eye, that covers the
// glow's silhouette (positions relative to the camera eye); the pixels it covers say the rest.
inline constexpr const char* kRimVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
uniform mat4 clipFromEyeRelative;
void main() { gl_Position = clipFromEyeRelative * vec4(position, 1.0); }
)";

// For each pixel the view ray eye + t * d (planet frame, / R); b: its distance from the planet's
// centre. The glow's opacity falls from `peak` at b = 1 to 0 at b = 1 + width, brighter on the
// side the sun lights. Drawn with glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA) before the
// planet, which covers its inner part.
inline constexpr const char* kRimFragment = R"(#version 330 core
uniform mat3 rayFromPixel;  // OpenCV pixel (u, v, 1) -> view direction, planet frame
uniform vec3 eye;           // the camera's centre, / R
uniform float imageHeight;
uniform vec3 sun;
uniform vec3 glow;
uniform float peak, width;
out vec4 colour;
void main() {
  // GL's window origin is the bottom-left pixel corner; OpenCV's pixel centres are integers
  // from the top-left.
  vec2 px = vec2(gl_FragCoord.x - 0.5, imageHeight - gl_FragCoord.y - 0.5);
  vec3 d = normalize(rayFromPixel * vec3(px, 1.0));
  float t = -dot(eye, d);
  if (t <= 0.0) discard;  // the centre is behind the camera
  vec3 c = eye + t * d;   // the ray's closest point to the centre
  float b = length(c);
  float x = clamp((b - 1.0) / width, 0.0, 1.0);
  if (x >= 1.0) discard;
  float fall = (1.0 - x) * (1.0 - x);
  float light = mix(0.25, 1.0, smoothstep(-0.3, 0.5, dot(c / b, sun)));
  colour = vec4(glow, peak * fall * light);
}
)";

}  // namespace ps::render
