#pragma once
// The AR view's board shadow and atmosphere rim (docs/RENDERING.md, "Board shadow and
// atmosphere"): drawn by PlanetRenderer::renderAR after the camera image and before the planet,
// when RenderStyle asks for them and the planet is a sphere. Neither tests nor writes depth.
//   * board shadow: the planet's sphere (radius R) in the sun's light, cast onto the board plane
//     {p : p . up = -R} (the planet stands on it), soft between 0.85 R and 1.15 R of the ray's
//     distance from the centre; it darkens the video (x 1 - 0.5 shadow);
//   * rim: a thin sky-blue glow just outside the planet's silhouette, 4 % of R wide, brighter
//     on the lit side.
#include <Eigen/Core>

#include "terrain/camera.hpp"

namespace ps::render {

struct BoardShadowLook {
  double inner = 0.85, outer = 1.15;  // full shadow / none, distance from the centre / R
  double strength = 0.5;              // the video is multiplied by 1 - strength at full shadow
  double reach = 8;                   // the quad's extent from the contact point, / R
};

struct RimLook {
  double width = 0.04;                                           // of R, outside the silhouette
  double peak = 0.6;                                             // opacity at the silhouette
  Eigen::Vector3f colour = Eigen::Vector3f(0.55f, 0.78f, 1.0f);  // RGB
};

class AtmospherePasses {
 public:
  // Needs a current OpenGL 3.3 context; throws std::runtime_error if a shader does not build.
  AtmospherePasses();
  ~AtmospherePasses();
  AtmospherePasses(const AtmospherePasses&) = delete;
  AtmospherePasses& operator=(const AtmospherePasses&) = delete;

  // Into the bound framebuffer (its viewport the camera's image). `sun` and `up` (the board's
  // normal) are unit vectors in the planet frame; R > 0 the planet's radius. Nothing is drawn
  // for a sun at or below the board.
  void drawBoardShadow(const terrain::Camera& camera, double R, const Eigen::Vector3d& sun,
                       const Eigen::Vector3d& up, const BoardShadowLook& look = {});
  void drawRim(const terrain::Camera& camera, double R, const Eigen::Vector3d& sun,
               const RimLook& look = {});

 private:
  unsigned shadowProgram_ = 0, rimProgram_ = 0;
  unsigned quadVao_ = 0, quadBuffer_ = 0;  // the pass's quad: eye-relative, / R
};

}  // namespace ps::render
