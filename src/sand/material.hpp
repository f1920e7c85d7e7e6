#pragma once
#include <string>
#include <vector>

namespace ps::sand {

// What a granular material does when it settles. One material is chosen per tool (the tool hands
// it to the settler with the region it changed); docs/SAND.md lists the presets and where each
// number comes from.
//
// Thermal erosion (paper 004, section 3.2) uses talusDeg, erosionRate, talusTolerance, cohesion.
// Drift-diffusion (paper 002) uses diffusion, frictionInverse, reposeDeg, reposeTolerance,
// cohesion.
struct Material {
  std::string name = "sand";

  // Thermal erosion: material moves from a vertex to a lower neighbour (of 8) only where the
  // height difference exceeds tan(talus) * distance + cohesion.
  double talusDeg = 30.0;  // (0, 90)
  // c in (0, 1]: a vertex gives away c * (1/2) * its largest excess per step (Musgrave's rule,
  // as paper 004 uses it), capped per receiver so that the step obeys a maximum principle.
  double erosionRate = 1.0;
  // A link rests once its excess is at most talusTolerance * tan(talus) * distance: settled
  // slopes are at most (1 + talusTolerance) tan(talus) (+ cohesion / distance). [1e-9, 0.1].
  double talusTolerance = 1e-3;

  // Drift-diffusion (paper 002): dh/dt = div(D w grad h) - div(F / zeta).
  double diffusion = 1.0;           // D, in reference cells^2 per time unit (>= 0)
  double frictionInverse = 4.0e-4;  // zeta^-1 (>= 0): drift per unit tool force
  double reposeDeg = 45.0;          // alpha, the angle of repose, (0, 90)
  // A face rests once its weight w = clamp((angle - alpha) / (90 deg - alpha), 0, 1) is at most
  // this. [1e-9, 0.1].
  double reposeTolerance = 1e-3;

  // Height difference (m) a material holds between neighbours at any slope (0 for dry sand).
  double cohesion = 0.0;

  // Throws core::InputError naming the first bad field and its value.
  void validate() const;

  double tanTalus() const;

  // Presets (docs/SAND.md, "Materials"): paper 004's sand talus, paper 002's Figure 4 values.
  static Material sand();
  static Material mud();
  static Material pebbles();
  // By name (one of presetNames()); throws core::InputError otherwise.
  static Material preset(const std::string& name);
  // "sand", "mud", "pebbles": what a user may choose (`--material`, the live panel).
  static const std::vector<std::string>& presetNames();

  bool operator==(const Material&) const = default;
};

}  // namespace ps::sand
